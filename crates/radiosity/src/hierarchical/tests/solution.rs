//! Whole solutions against what is known exactly: the furnace, energy balance in closed
//! boxes, coincident twins, the exact system of the same leaves, and vertex values continuous
//! across T-vertices.

use super::*;

/// The furnace (every surface emits E and reflects ρ, closed, with a floating block that
/// occludes): B = E/(1 − ρ) exactly. Per input surface the area mean is held to 0.2 %; per
/// leaf, a coarse link's value pushed to the receiver's quarters still misses the kernel's
/// variation within them, most at the box's corners, so every leaf is held to 10 % and the
/// RMS to 2.5 % (the figures measured: `docs/notes/hierarchical.md`).
#[test]
fn furnace_is_uniform() {
    let scene = crate::scene::builtin::furnace();
    let s = solve(
        &scene,
        Params {
            tolerance: 1e-8,
            ..Default::default()
        },
    );
    let exact = crate::scene::builtin::FURNACE_EMISSION.g
        / (1.0 - crate::scene::builtin::FURNACE_REFLECTANCE.g);
    let mut per = vec![(0.0, 0.0); scene.polygons.len()];
    let (mut sq, mut area) = (0.0, 0.0);
    for (p, b) in s.mesh.patches.iter().zip(&s.radiosity) {
        let rel = b.g / exact - 1.0;
        assert!(rel.abs() < 0.1, "leaf at {:?}: {}", p.centre, b.g);
        sq += rel * rel * p.area as f64;
        area += p.area as f64;
        per[p.surface as usize].0 += b.g * p.area as f64;
        per[p.surface as usize].1 += p.area as f64;
    }
    assert!((sq / area).sqrt() < 0.025, "RMS {}", (sq / area).sqrt());
    for (k, (b, a)) in per.iter().enumerate() {
        let mean = b / a;
        assert!((mean / exact - 1.0).abs() < 0.002, "surface {k}: {mean}");
    }
}

/// A closed cube whose ceiling emits: nothing escapes, so the power absorbed equals the
/// power emitted, up to the links' estimation error, held to 0.5 %
/// (`docs/notes/hierarchical.md`).
#[test]
fn energy_balances_in_a_closed_cube() {
    let grey = Material::diffuse("grey", Rgb::splat(0.6));
    let lamp = Material::emitter("lamp", Rgb::splat(0.6), Rgb::splat(1.0));
    let s = solve(
        &cube(vec![grey, lamp], [0, 1, 0, 0, 0, 0]),
        Params::default(),
    );
    let i = &s.info;
    let e = i.emitted.g;
    assert!((i.absorbed.g - e).abs() < 0.005 * e, "{:?}", i);
    assert!(i.escaped.g.abs() < 0.005 * e, "{:?}", i);
}

/// Coincident copies (a scene included twice) are one surface ([`crate::mesh::Coincidence`]):
/// the mesher keeps the first of each pair and the copy reports its radiosity. The doubled
/// furnace has each copy at the single furnace's E/(1 − ρ), within the furnace's 0.2 %; the
/// doubled closed cube balances its energy as the single one does.
#[test]
fn twins_are_one_surface() {
    let furnace = crate::scene::builtin::furnace();
    let mut doubled = furnace.clone();
    doubled.polygons.extend(furnace.polygons.iter().cloned());
    let s = solve(
        &doubled,
        Params {
            tolerance: 1e-8,
            ..Default::default()
        },
    );
    assert_eq!(s.mesh.coincident.merged, furnace.polygons.len());
    let (e, rho) = (
        crate::scene::builtin::FURNACE_EMISSION.g,
        crate::scene::builtin::FURNACE_REFLECTANCE.g,
    );
    let exact = e / (1.0 - rho);
    let per = s.mesh.surface_means(&s.radiosity, doubled.polygons.len());
    let n = furnace.polygons.len();
    for k in 0..n {
        let (a, b) = (per[k].g, per[k + n].g);
        assert!(
            (a / exact - 1.0).abs() < 0.002,
            "surface {k}: {a} vs {exact}"
        );
        assert_eq!(a, b, "surface {k} and its copy");
    }
    let grey = Material::diffuse("grey", Rgb::splat(0.6));
    let lamp = Material::emitter("lamp", Rgb::splat(0.6), Rgb::splat(1.0));
    let single = cube(vec![grey, lamp], [0, 1, 0, 0, 0, 0]);
    let mut cube2 = single.clone();
    cube2.polygons.extend(single.polygons.iter().cloned());
    let s = solve(&cube2, Params::default());
    let i = &s.info;
    let e = i.emitted.g;
    assert!((i.absorbed.g - e).abs() < 0.005 * e, "{:?}", i);
    assert!(i.escaped.g.abs() < 0.005 * e, "{:?}", i);
}

/// At the leaf level of a small hierarchy, the exact system (analytic factors between the
/// leaves of a convex cube, where nothing occludes, solved by LU) agrees with the
/// hierarchical solution: the area-weighted mean difference is the links' approximation
/// error, held to 2 % and every leaf to 15 % (`docs/notes/hierarchical.md`).
#[test]
fn leaves_agree_with_the_exact_leaf_system() {
    let grey = Material::diffuse("grey", Rgb::splat(0.6));
    let lamp = Material::emitter("lamp", Rgb::splat(0.3), Rgb::splat(1.0));
    let scene = cube(vec![grey, lamp], [0, 1, 0, 0, 0, 0]);
    let s = solve(
        &scene,
        Params {
            link_error: 1e-3,
            tolerance: 1e-8,
            ..Default::default()
        },
    );
    let n = s.mesh.len();
    assert!((50..3000).contains(&n), "{n} leaves");
    let exact = exact_leaf_solution(&s);
    let (mut diff, mut total, mut worst) = (0.0, 0.0, 0.0f64);
    for k in 0..n {
        let (h, x) = (s.radiosity[k].g, exact.radiosity[k].g);
        worst = worst.max((h - x).abs() / x);
        diff += (h - x).abs() * s.system.area[k];
        total += x * s.system.area[k];
    }
    assert!(worst < 0.15, "{worst}");
    assert!(diff / total < 0.02, "{}", diff / total);
}

/// Vertex values are continuous across T-vertices: every mesh vertex lying inside the
/// edge of a leaf (found here by brute-force geometry, not by the mesh's own list) has the
/// value that the leaf interpolates there.
#[test]
fn vertex_values_are_continuous_across_t_vertices() {
    let scene = crate::scene::builtin::by_name("cornell").unwrap();
    let s = solve(
        &scene,
        Params {
            link_error: 1e-4,
            ..Default::default()
        },
    );
    assert!(!s.mesh.hanging.is_empty());
    let values = s.vertex_display_radiosity();
    // Vertices by surface, for the brute-force search.
    let mut by_surface: std::collections::HashMap<u32, Vec<u32>> = Default::default();
    for p in &s.mesh.patches {
        let n = if p.is_triangle() { 3 } else { 4 };
        by_surface
            .entry(p.surface)
            .or_default()
            .extend(&p.vertices[..n]);
    }
    for v in by_surface.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    let mut checked = 0;
    for p in &s.mesh.patches {
        let n = if p.is_triangle() { 3 } else { 4 };
        for k in 0..n {
            let (a, b) = (p.vertices[k], p.vertices[(k + 1) % n]);
            let (pa, pb) = (s.mesh.vertices[a as usize], s.mesh.vertices[b as usize]);
            let len = (pb - pa).length();
            for &v in &by_surface[&p.surface] {
                let pv = s.mesh.vertices[v as usize];
                let (da, db, dv) = (pa.as_dvec3(), pb.as_dvec3(), pv.as_dvec3());
                let t = (dv - da).dot(db - da) / (db - da).length_squared();
                let off = (dv - (da + (db - da) * t)).length() as f32;
                let t = t as f32;
                if t <= 1e-4 || t >= 1.0 - 1e-4 || off > 1e-4 * len {
                    continue;
                }
                let t = (dv - da).dot(db - da) / (db - da).length_squared();
                let want = values[a as usize] * (1.0 - t) + values[b as usize] * t;
                assert!(
                    values[v as usize].max_abs_diff(want)
                        <= 1e-4 * values[a as usize].max_abs_diff(values[b as usize]) + 1e-12,
                    "vertex {v} at {pv:?} on edge ({a}, {b}) {pa:?} {pb:?} t {t}: {:?} vs {want:?}; constraint {:?}",
                    values[v as usize],
                    s.mesh.hanging.iter().find(|h| h[0] == v)
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked} T-vertices");
}
