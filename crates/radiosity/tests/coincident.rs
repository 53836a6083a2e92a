//! Coincident polygons are one surface in every method ([`radiosity::mesh::Coincidence`]): a
//! scene with every polygon given twice is the single scene, each copy reporting its surface;
//! a thousand copies mesh as one; what is merged and what is not.

use radiosity::accel::Bvh;
use radiosity::color::Rgb;
use radiosity::geom::Vec3;
use radiosity::mesh::{Coincidence, Mesh, MeshParams};
use radiosity::observe::Silent;
use radiosity::pipeline::{self, Method, Settings, Uniform};
use radiosity::render::RenderParams;
use radiosity::scene::{builtin, Material, Polygon, Scene};
use radiosity::solve::{Solver, SolverParams};

fn doubled(scene: &Scene) -> Scene {
    let mut d = scene.clone();
    d.polygons.extend(scene.polygons.iter().cloned());
    d
}

fn settings(solver: Solver) -> Settings {
    Settings::from(Uniform {
        mesh: MeshParams::Patches(300),
        solver,
        params: SolverParams {
            tolerance: 1e-3,
            ..SolverParams::default()
        },
        ..Uniform::default()
    })
}

/// The Cornell box with every polygon given twice, solved by every solver and by hierarchical
/// radiosity: each copy reports the single box's per-surface radiosity, bit for bit (the
/// mesher keeps one polygon of each pair, so the system, the rays and the solution are the
/// single box's; before, progressive refinement and stochastic Jacobi put each copy 100–120 %
/// away from the single box's surface).
#[test]
fn every_solver_gives_each_copy_the_single_boxs_surface() {
    let single = builtin::cornell();
    let two = doubled(&single);
    let n = single.polygons.len();
    let mut methods: Vec<(String, Settings)> = Solver::ALL
        .iter()
        .map(|&s| (format!("{s:?}"), settings(s)))
        .collect();
    methods.push((
        "hierarchical".into(),
        Settings {
            method: Method::Hierarchical(Default::default()),
            ..settings(Solver::Progressive)
        },
    ));
    for (name, s) in &methods {
        let one = pipeline::solve(&single, s, &Silent).unwrap();
        let dup = pipeline::solve(&two, s, &Silent).unwrap();
        assert_eq!(dup.mesh.coincident.merged, n, "{name}");
        assert_eq!(dup.mesh.len(), one.mesh.len(), "{name}");
        let a = one.mesh.surface_means(&one.radiosity, n);
        let b = dup.mesh.surface_means(&dup.radiosity, 2 * n);
        for k in 0..n {
            assert_eq!(a[k], b[k], "{name}: surface {k}");
            assert_eq!(a[k], b[k + n], "{name}: the copy of surface {k}");
            assert!(a[k].max_channel() > 0.0, "{name}: surface {k} is dark");
        }
        assert_eq!(
            one.info.emitted, dup.info.emitted,
            "{name}: emission counted once"
        );
    }
}

/// The final gather and the path tracer see one surface too: the doubled box's pictures are
/// the single box's, pixel for pixel, and its path-traced surface means give each copy the
/// surface's.
#[test]
fn the_gather_and_the_path_tracer_see_one_surface() {
    let single = builtin::cornell();
    let two = doubled(&single);
    let params = RenderParams {
        width: 24,
        height: 24,
        samples_per_pixel: 2,
        ..Default::default()
    };
    let s = settings(Solver::Progressive);
    let one = pipeline::solve(&single, &s, &Silent).unwrap();
    let dup = pipeline::solve(&two, &s, &Silent).unwrap();
    let camera = one.default_camera(&single);
    let gather = radiosity::render::gather::GatherParams {
        cache_samples: 64,
        ..Default::default()
    };
    let a = one.render_gather(&camera, &params, gather, &Silent);
    let b = dup.render_gather(&camera, &params, gather, &Silent);
    assert!(a.pixels == b.pixels, "the gather's pictures differ");
    let a = pipeline::path_trace(&single, &camera, &params, &Silent).unwrap();
    let b = pipeline::path_trace(&two, &camera, &params, &Silent).unwrap();
    assert!(a.pixels == b.pixels, "the path tracer's pictures differ");
    let n = single.polygons.len();
    let a = pipeline::path_surface_means(&single, 20_000, 3).unwrap();
    let b = pipeline::path_surface_means(&two, 20_000, 3).unwrap();
    for k in 0..n {
        assert_eq!(b[k].0, b[k + n].0, "surface {k} and its copy");
        // Both runs draw as many samples per surface (the copies add none).
        assert_eq!(a[k].0, b[k].0, "surface {k}");
    }
}

/// A thousand copies of the floor cost what one costs: the mesh, and so the ray caster's tree,
/// is the single box's (before, each ray near them tested all 1,000, and `form-factors` took
/// 47 s for 15,294 patches where 200 were asked).
#[test]
fn a_thousand_copies_mesh_as_one() {
    let single = builtin::cornell();
    let mut many = single.clone();
    for _ in 0..999 {
        many.polygons.push(single.polygons[0].clone());
    }
    let c = Coincidence::find(&many);
    assert_eq!(c.merged, 999);
    assert_eq!(c.mixed, 0);
    assert!(c.warning().unwrap().starts_with("999 coincident polygons"));
    let one = Mesh::build(&single, MeshParams::Patches(200)).unwrap();
    let all = Mesh::build(&many, MeshParams::Patches(200)).unwrap();
    assert_eq!(one.patches, all.patches);
    assert_eq!(one.vertices, all.vertices);
    let (a, b) = (Bvh::build(&one).info(), Bvh::build(&all).info());
    assert_eq!((a.nodes, a.triangles), (b.nodes, b.triangles));
}

fn square(z: f32, side: f32, up: bool) -> Polygon {
    let v = Vec3::new;
    let mut vs = vec![
        v(0.0, 0.0, z),
        v(side, 0.0, z),
        v(side, side, z),
        v(0.0, side, z),
    ];
    if !up {
        vs.reverse();
    }
    Polygon {
        vertices: vs,
        material: 0,
        line: 0,
        group: 0,
    }
}

/// What is merged: the same corners in any order and any starting corner, within 10⁻⁶ of the
/// scene's size, facing the same way. What is not: a polygon back to back with another (the
/// two sides of a wall), a polygon a little larger, or one 10⁻³ of the scene away.
#[test]
fn the_same_corners_facing_the_same_way_and_nothing_else() {
    let grey = Material::diffuse("grey", Rgb::splat(0.5));
    let mut s = Scene::of_polygons("t", grey, vec![]);
    let base = square(0.0, 1.0, true);
    let mut rotated = base.clone();
    rotated.vertices.rotate_left(1);
    let mut nudged = base.clone();
    nudged.vertices[2].x += 1e-8;
    let mut far = base.clone();
    for p in &mut far.vertices {
        p.z += 1e-3;
    }
    s.polygons = vec![
        base.clone(),
        rotated,
        nudged,
        square(0.0, 1.0, false),
        square(0.0, 1.001, true),
        far,
        square(5.0, 1.0, true),
    ];
    let c = Coincidence::find(&s);
    assert_eq!(c.of, vec![0, 0, 0, 3, 4, 5, 6]);
    assert_eq!(c.merged, 2);
}

/// Coincident polygons of different materials are one surface with one material: the first
/// emitter of the group, else the first polygon (a lamp laid on a ceiling panel of its shape
/// stays a lamp); the warning counts the copies whose material differs.
#[test]
fn mixed_materials_take_the_first_emitter_or_the_first_polygon() {
    let grey = Material::diffuse("grey", Rgb::splat(0.5));
    let red = Material::diffuse("red", Rgb::new(0.6, 0.1, 0.1));
    let lamp = Material::emitter("lamp", Rgb::splat(0.2), Rgb::splat(10.0));
    let mut s = Scene::of_polygons("t", grey, vec![]);
    s.materials.push(red);
    s.materials.push(lamp);
    let p = |z: f32, m: usize| {
        let mut q = square(z, 1.0, true);
        q.material = m;
        q
    };
    s.polygons = vec![p(0.0, 0), p(0.0, 1), p(1.0, 0), p(1.0, 2), p(1.0, 0)];
    let c = Coincidence::find(&s);
    assert_eq!(c.of, vec![0, 0, 3, 3, 3]);
    assert_eq!((c.merged, c.mixed), (3, 3));
    let w = c.warning().unwrap();
    assert!(w.contains("3 of them with another material"), "{w}");
    let mesh = Mesh::build(&s, MeshParams::Faces).unwrap();
    let materials: Vec<u32> = mesh.patches.iter().map(|p| p.material).collect();
    assert_eq!(materials, vec![0, 2]);
}

/// A partial overlap (a panel covering half of a closed cube's floor, in the floor's plane)
/// is two surfaces: the ray caster gives the overlap to one of them, the same one from every
/// side, so no light is lost or made: progressive refinement closes its books in the closed
/// cube, as without the panel.
#[test]
fn a_partial_overlap_stays_two_surfaces_and_conserves_energy() {
    let cube = builtin::by_name("cube").unwrap();
    let floor = cube
        .polygons
        .iter()
        .position(|p| radiosity::scene::vector_area(&p.vertices).normalize().z > 0.9)
        .or_else(|| {
            cube.polygons
                .iter()
                .position(|p| radiosity::scene::vector_area(&p.vertices).normalize().y > 0.9)
        })
        .expect("the cube has a floor");
    let f = &cube.polygons[floor];
    // Half the floor: the corners 0 and 1, and the midpoints of the two other edges.
    let v = &f.vertices;
    let half = Polygon {
        vertices: vec![v[0], v[1], (v[1] + v[2]) * 0.5, (v[0] + v[3]) * 0.5],
        ..f.clone()
    };
    let mut s = cube.clone();
    s.polygons.push(half);
    assert_eq!(Coincidence::find(&s).merged, 0);
    let sol = pipeline::solve(&s, &settings(Solver::Progressive), &Silent).unwrap();
    let i = sol.info;
    assert!(
        i.escaped.max_channel() < 1e-2 * i.emitted.max_channel(),
        "escaped {} of {}",
        i.escaped,
        i.emitted
    );
    let balance = i.emitted - i.absorbed - i.escaped - i.unshot;
    assert!(balance.max_abs_diff(Rgb::BLACK) < 1e-9 * i.emitted.max_channel());
}
