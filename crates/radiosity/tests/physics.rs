//! The engine against physics: closed-form form factors (Howell's catalogue), row sums in a
//! closed enclosure, reciprocity, the white furnace, energy balance, and determinism across
//! thread counts. Tolerances come from the Monte Carlo estimator's known variance (eq. 7 of
//! Szirmay-Kalos & Márton (1995): σ² = F(1 − F)/n).

use radiosity::accel::Bvh;
use radiosity::color::Rgb;
use radiosity::formfactor::monte_carlo::{estimate_row, RowScratch};
use radiosity::geom::Vec3;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::pipeline::{self, Settings, Uniform};
use radiosity::scene::{builtin, Material, Polygon, Scene};
use radiosity::solve::SolverParams;

fn quad(v: [[f32; 3]; 4]) -> Polygon {
    Polygon {
        vertices: v.iter().map(|p| Vec3::from_array(*p)).collect(),
        material: 0,
        line: 0,
        group: 0,
    }
}

fn two_patch_scene(a: Polygon, b: Polygon) -> Scene {
    Scene {
        name: "pair".into(),
        materials: vec![Material::emitter("m", Rgb::splat(0.5), Rgb::splat(1.0))],
        polygons: vec![a, b],
        ..Default::default()
    }
}

/// F̂_{0→1} with `n` rays, and its standard deviation by eq. 7.
fn factor(scene: &Scene, n: u32) -> (f64, f64, Vec<(u32, f32)>) {
    let mesh = Mesh::build(scene, MeshParams::Faces).unwrap();
    assert_eq!(mesh.len(), 2);
    let bvh = Bvh::build(&mesh);
    let mut row = Vec::new();
    estimate_row(
        &mesh,
        &bvh,
        0,
        n,
        11,
        0,
        &mut RowScratch::default(),
        &mut row,
    );
    let f = row.iter().find(|e| e.0 == 1).map_or(0.0, |e| e.1 as f64);
    (f, (f * (1.0 - f) / n as f64).sqrt(), row)
}

/// Howell's catalogue, configuration C-11: two parallel, directly opposed unit squares at
/// distance 1 have F = 0.19982.
#[test]
fn parallel_unit_squares_match_howell() {
    let bottom = quad([[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]); // faces +z
    let top = quad([[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]]); // faces −z
    let n = 1_000_000;
    let (f, sigma, _) = factor(&two_patch_scene(bottom, top), n);
    assert!((f - 0.19982).abs() < 4.0 * sigma, "F = {f}, σ = {sigma}");
}

/// Howell's catalogue, configuration C-14: two perpendicular unit squares sharing an edge have
/// F = 0.20004.
#[test]
fn perpendicular_unit_squares_match_howell() {
    let floor = quad([[0., 0., 0.], [1., 0., 0.], [1., 0., 1.], [0., 0., 1.]]);
    let floor = Polygon {
        vertices: floor.vertices.into_iter().rev().collect(), // face +y
        ..floor
    };
    let wall = quad([[0., 0., 0.], [0., 1., 0.], [1., 1., 0.], [1., 0., 0.]]);
    let wall = Polygon {
        vertices: wall.vertices.into_iter().rev().collect(), // face +z
        ..wall
    };
    let scene = two_patch_scene(floor, wall);
    let mesh = Mesh::build(&scene, MeshParams::Faces).unwrap();
    assert!(mesh.patches[0].normal.y > 0.99 && mesh.patches[1].normal.z > 0.99);
    let n = 1_000_000;
    let (f, sigma, _) = factor(&scene, n);
    assert!((f - 0.20004).abs() < 4.0 * sigma, "F = {f}, σ = {sigma}");
}

/// Reciprocity A_i F_ij = A_j F_ji between unequal patches, within the combined 4σ.
#[test]
fn reciprocity_between_unequal_patches() {
    // A 1 × 1 square below a 2 × 2 square, offset, 1 apart.
    let small = quad([[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]);
    let big = quad([[0.5, 0., 1.], [0.5, 2., 1.], [2.5, 2., 1.], [2.5, 0., 1.]]);
    let n = 400_000;
    let (f01, s01, _) = factor(&two_patch_scene(small.clone(), big.clone()), n);
    let (f10, s10, _) = factor(&two_patch_scene(big, small), n);
    let (a0, a1) = (1.0, 4.0);
    let diff = (a0 * f01 - a1 * f10).abs();
    let sigma = ((a0 * s01).powi(2) + (a1 * s10).powi(2)).sqrt();
    assert!(
        f01 > 0.1 && diff < 4.0 * sigma,
        "A0F01 = {}, A1F10 = {}, σ = {sigma}",
        a0 * f01,
        a1 * f10
    );
}

/// In a closed enclosure every ray hits a front side: every row of F̂ sums to 1 (a test of the
/// ray caster's watertightness at shared edges and of the ray offsets at corners).
#[test]
fn rows_sum_to_one_in_a_closed_scene() {
    let scene = builtin::furnace();
    let mesh = Mesh::build(&scene, MeshParams::Patches(400)).unwrap();
    let bvh = Bvh::build(&mesh);
    let mut scratch = RowScratch::default();
    let mut row = Vec::new();
    let n = 2000;
    let mut worst = 0.0f64;
    for i in 0..mesh.len() {
        estimate_row(&mesh, &bvh, i, n, 5, 0, &mut scratch, &mut row);
        let sum: f64 = row.iter().map(|e| e.1 as f64).sum();
        worst = worst.max((sum - 1.0).abs());
        assert!(row.iter().all(|e| e.0 as usize != i), "a patch hit itself");
    }
    // Exactly 1 up to f32 rounding of k/n, unless rays leak (one lost ray is 1/n = 5e-4).
    assert!(worst < 1e-4, "worst |row sum − 1| = {worst}");
}

/// A Monte Carlo row lists each patch hit once, in order, with `k/n` for its `k > 0` hits,
/// and is the same whether its buffers are fresh or were used for other rows before (the
/// bitmap that lists the patches hit is left clear by every row).
#[test]
fn rows_are_sorted_and_do_not_depend_on_the_buffers_history() {
    let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(2000)).unwrap();
    let bvh = Bvh::build(&mesh);
    let mut reused = RowScratch::default();
    let (mut row, mut fresh_row) = (Vec::new(), Vec::new());
    let n = 3000;
    for i in (0..mesh.len()).step_by(37) {
        estimate_row(&mesh, &bvh, i, n, 9, 1, &mut reused, &mut row);
        let mut fresh = RowScratch::default();
        estimate_row(&mesh, &bvh, i, n, 9, 1, &mut fresh, &mut fresh_row);
        assert_eq!(row, fresh_row, "row {i}");
        assert!(
            row.windows(2).all(|w| w[0].0 < w[1].0),
            "row {i} not sorted"
        );
        let hits: f64 = row
            .iter()
            .map(|&(j, f)| {
                let k = f as f64 * n as f64;
                assert!((j as usize) < mesh.len() && j as usize != i);
                assert!(
                    k >= 0.5 && (k - k.round()).abs() < 1e-3,
                    "row {i}: {k} hits"
                );
                k.round()
            })
            .sum();
        assert!(hits <= n as f64, "row {i}: {hits} hits of {n} rays");
    }
}

fn furnace_solution(rays: u32, patches: usize) -> pipeline::Solution {
    let settings = Settings::from(Uniform {
        mesh: MeshParams::Patches(patches),
        form_factors: radiosity::formfactor::Params {
            rays,
            seed: 3,
            ..radiosity::formfactor::Params::shooting()
        },
        params: SolverParams {
            tolerance: 1e-7,
            ..SolverParams::default()
        },
        ..Uniform::default()
    });
    pipeline::solve(&builtin::furnace(), &settings, &radiosity::observe::Silent).unwrap()
}

/// The white furnace: uniform ρ and E in a closed enclosure give B = E/(1 − ρ) everywhere.
/// The area-weighted mean is exact for any estimate whose rows sum to 1; each patch deviates by
/// the Monte Carlo error of what it gathers, relative σ_j = ρ/√(n A_j/Ā) (its expected number of
/// hits is n A_j/Ā), and that error halves when n quadruples.
#[test]
fn furnace_gives_e_over_one_minus_rho() {
    let rho = builtin::FURNACE_REFLECTANCE;
    let exact = Rgb::new(
        1.0 / (1.0 - rho.r),
        1.0 / (1.0 - rho.g),
        1.0 / (1.0 - rho.b),
    );
    let mut rms = Vec::new();
    for rays in [256, 1024] {
        let s = furnace_solution(rays, 600);
        assert!(s.info.converged);
        let total_area: f64 = s.system.area.iter().sum();
        let mean_area = total_area / s.system.area.len() as f64;
        let mean: Rgb = s
            .radiosity
            .iter()
            .zip(&s.system.area)
            .map(|(b, a)| *b * *a)
            .sum::<Rgb>()
            / total_area;
        for (m, x) in mean.to_array().iter().zip(exact.to_array()) {
            assert!((m / x - 1.0).abs() < 1e-5, "area-weighted mean {m} vs {x}");
        }
        let mut sum_z2 = 0.0;
        let mut sum_rel2 = 0.0;
        for (b, a) in s.radiosity.iter().zip(&s.system.area) {
            for (c, (bx, ex)) in b.to_array().iter().zip(exact.to_array()).enumerate() {
                let r = rho.to_array()[c];
                let rel = bx / ex - 1.0;
                let sigma = r / (rays as f64 * a / mean_area).sqrt();
                assert!(rel.abs() < 6.0 * sigma, "patch off by {rel} (σ {sigma})");
                if c == 1 {
                    sum_z2 += (rel / sigma).powi(2);
                    sum_rel2 += rel * rel;
                }
            }
        }
        let n = s.radiosity.len() as f64;
        let z_rms = (sum_z2 / n).sqrt();
        // The predicted σ is right to within a factor: the z-scores' RMS is near 1.
        assert!((0.5..1.6).contains(&z_rms), "RMS z-score {z_rms}");
        rms.push((sum_rel2 / n).sqrt());
    }
    let ratio = rms[0] / rms[1];
    assert!(
        (1.5..2.7).contains(&ratio),
        "error ratio for 4× rays: {ratio} (1/√n predicts 2)"
    );
}

/// Energy balance of a converged open scene: emitted = absorbed + escaped + unshot, and the
/// absorbed power recomputed from the radiosities, Σ (1 − ρ_j)/ρ_j (B_j − E_j) A_j, agrees.
#[test]
fn energy_balance_in_the_cornell_box() {
    let settings = Settings::from(Uniform {
        mesh: MeshParams::Patches(1500),
        ..Uniform::default()
    });
    let s = pipeline::solve(&builtin::cornell(), &settings, &radiosity::observe::Silent).unwrap();
    let i = s.info;
    assert!(i.converged && i.unshot_fraction <= 0.01);
    let balance = i.emitted - i.absorbed - i.escaped - i.unshot;
    assert!(
        balance.max_abs_diff(Rgb::BLACK) < 1e-9 * i.emitted.max_channel(),
        "{balance}"
    );
    // The box is open at the front: some light leaves.
    assert!(i.escaped.sum() > 0.05 * i.emitted.sum());
    let mut absorbed = Rgb::BLACK;
    for k in 0..s.system.area.len() {
        let rho = s.system.reflectance[k];
        let gathered = s.radiosity[k] - s.system.emission[k];
        absorbed += Rgb::new(
            (1.0 - rho.r) / rho.r * gathered.r,
            (1.0 - rho.g) / rho.g * gathered.g,
            (1.0 - rho.b) / rho.b * gathered.b,
        ) * s.system.area[k];
    }
    assert!(absorbed.max_abs_diff(i.absorbed) < 1e-9 * i.emitted.max_channel());
    // The walls' colours bleed: the white floor next to the red wall is redder than next to
    // the green wall.
    let floor_near = |x_sign: f32| {
        let mut c = Rgb::BLACK;
        for (k, p) in s.mesh.patches.iter().enumerate() {
            if p.surface == 0 && (p.centre.x - 278.0) * x_sign > 200.0 && p.centre.z > 400.0 {
                c += s.radiosity[k];
            }
        }
        c
    };
    let (red_side, green_side) = (floor_near(1.0), floor_near(-1.0));
    assert!(red_side.r / red_side.g > green_side.r / green_side.g);
}

/// The same seed gives bit-identical radiosities and pictures with 1 and 2 threads.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let settings = Settings::from(Uniform {
                mesh: MeshParams::Patches(800),
                ..Uniform::default()
            });
            let scene = builtin::cornell();
            let s = pipeline::solve(&scene, &settings, &radiosity::observe::Silent).unwrap();
            let params = radiosity::render::RenderParams {
                width: 48,
                height: 48,
                samples_per_pixel: 2,
                seed: 9,
            };
            let img = s.render(&scene.camera.unwrap(), &params, &radiosity::observe::Silent);
            (s.radiosity, img.pixels)
        })
    };
    let (b1, p1) = run(1);
    let (b2, p2) = run(2);
    assert!(b1 == b2, "radiosities differ between 1 and 2 threads");
    assert!(p1 == p2, "pictures differ between 1 and 2 threads");
}

/// `scene` solved by `solver` on about `patches` patches with stochastic Jacobi's
/// `iteration_rays` and `gather_rays` (the defaults otherwise, or `tolerance` if given).
fn solved(
    scene: &Scene,
    patches: usize,
    solver: radiosity::solve::Solver,
    (iteration_rays, gather_rays): (u32, u32),
    tolerance: Option<f64>,
) -> pipeline::Solution {
    let defaults = SolverParams::default();
    let params = SolverParams {
        iteration_rays,
        gather_rays,
        tolerance: tolerance.unwrap_or(defaults.tolerance),
        ..defaults
    };
    pipeline::solve(
        scene,
        &Settings::from(Uniform {
            mesh: MeshParams::Patches(patches),
            solver,
            params,
            ..Uniform::default()
        }),
        &radiosity::observe::Silent,
    )
    .unwrap()
}

/// Stochastic Jacobi's pass over the patches after each iteration runs in parallel over fixed
/// ranges of patches: on a mesh of several ranges (20,000 patches) one and two threads give
/// the same B and the same books, bit for bit, with the final gathering and without.
#[test]
fn stochastic_jacobi_on_many_patches_does_not_depend_on_the_threads() {
    let scene = builtin::cornell();
    for gather_rays in [0, 4] {
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let s = solved(
                        &scene,
                        20_000,
                        radiosity::solve::Solver::StochasticJacobi,
                        (4, gather_rays),
                        Some(0.05),
                    );
                    (s.radiosity, s.info.absorbed, s.info.escaped, s.info.unshot)
                })
        };
        let (one, two) = (on(1), on(2));
        assert!(one.0.len() > 16_384, "{} patches", one.0.len());
        assert!(
            one == two,
            "gather {gather_rays}: one thread and two differ"
        );
    }
}

/// Stochastic Jacobi's final gathering under a cover lying flush on a surface (a rug 0.7 ray
/// offsets above the Cornell box's floor): no light reaches the floor under the rug, as every
/// shooting method finds, so its reflected radiosity is 0. A gathering ray launched a ray offset
/// above the floor starts above the rug and sees the room, which made the covered floor as
/// bright as the rest. The rug itself is lit as usual.
#[test]
fn stochastic_jacobi_gathers_nothing_under_a_flush_cover() {
    let mut scene = builtin::cornell();
    let off = Bvh::build(&Mesh::build(&scene, MeshParams::Faces).unwrap()).ray_offset();
    let h = 0.7 * off;
    scene
        .materials
        .push(Material::diffuse("rug", Rgb::splat(0.5)));
    let rug = scene.polygons.len();
    scene.polygons.push(Polygon {
        material: scene.materials.len() - 1,
        ..quad([
            [300.0, h, 100.0],
            [100.0, h, 100.0],
            [100.0, h, 300.0],
            [300.0, h, 300.0],
        ])
    });
    // Stochastic Jacobi with its final gathering (64 rays a patch) and without.
    for (solver, gather_rays) in [
        (radiosity::solve::Solver::StochasticJacobi, 64),
        (radiosity::solve::Solver::StochasticJacobi, 0),
        (radiosity::solve::Solver::Progressive, 0),
    ] {
        let s = solved(&scene, 3000, solver, (64, gather_rays), None);
        let (mut under, mut open, mut lit) = ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0));
        for (k, p) in s.mesh.patches.iter().enumerate() {
            let a = p.area as f64;
            let b = s.radiosity[k].sum() * a;
            let c = p.centre;
            let inside = (110.0..290.0).contains(&c.x) && (110.0..290.0).contains(&c.z);
            let slot = match p.surface as usize {
                0 if inside => &mut under,
                0 if !(90.0..310.0).contains(&c.x) || !(90.0..310.0).contains(&c.z) => &mut open,
                x if x == rug => &mut lit,
                _ => continue,
            };
            slot.0 += a;
            slot.1 += b;
        }
        let mean = |x: (f64, f64)| x.1 / x.0;
        assert!(under.0 > 0.0 && lit.0 > 0.0);
        assert!(
            mean(under) < 1e-3 * mean(open),
            "{solver} (gather {gather_rays}): floor under the rug {} against {} in the open",
            mean(under),
            mean(open)
        );
        assert!(
            mean(lit) > 0.3 * mean(open),
            "{solver} (gather {gather_rays}): rug {}",
            mean(lit)
        );
    }
}
