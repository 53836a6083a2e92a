//! Refinement: where leaves crowd, links that see nothing dropped, and parameters refused.

use super::*;

/// A square lamp over a floor with a square occluder between them: the leaves crowd along
/// the shadow's edge. Leaves within 0.1 of the penumbra's middle line are more than twice
/// as dense (per unit area) as those elsewhere within 1.5 of the centre, though the lit
/// floor nearer the lamp has the steeper fall-off (`docs/notes/hierarchical.md`).
#[test]
fn refinement_concentrates_at_a_shadow_boundary() {
    let lamp = Material::emitter("lamp", Rgb::BLACK, Rgb::splat(10.0));
    let floor = Material::diffuse("floor", Rgb::splat(0.5));
    let black = Material::diffuse("occluder", Rgb::BLACK);
    let scene = Scene {
        name: "shadow".into(),
        materials: vec![lamp, floor, black],
        polygons: vec![
            // A small lamp at height 2 facing down; an occluder 0.6 wide at height 1
            // facing up (its back, black, faces the floor); the floor 4 × 4.
            quad(
                [
                    [-0.1, 2., -0.1],
                    [0.1, 2., -0.1],
                    [0.1, 2., 0.1],
                    [-0.1, 2., 0.1],
                ],
                0,
            ),
            quad(
                [
                    [-0.3, 1., -0.3],
                    [-0.3, 1., 0.3],
                    [0.3, 1., 0.3],
                    [0.3, 1., -0.3],
                ],
                2,
            ),
            quad(
                [[-2., 0., -2.], [-2., 0., 2.], [2., 0., 2.], [2., 0., -2.]],
                1,
            ),
        ],
        ..Scene::default()
    };
    let s = solve(&scene, Params::default());
    // The umbra/penumbra edge of the occluder's shadow is near |x| or |z| = 0.6.
    let (mut near, mut far) = ((0.0, 0usize), (0.0, 0usize));
    for p in &s.mesh.patches {
        if p.surface != 2 {
            continue;
        }
        let m = p.centre.x.abs().max(p.centre.z.abs());
        let d = (m - 0.6).abs();
        if d < 0.1 {
            near = (near.0 + p.area as f64, near.1 + 1);
        } else if m < 1.5 {
            far = (far.0 + p.area as f64, far.1 + 1);
        }
    }
    let density = |(a, c): (f64, usize)| c as f64 / a;
    assert!(
        density(near) > 2.0 * density(far),
        "near {near:?}, far {far:?}"
    );
}

/// A closed cube split by a wall (two one-sided faces back to back), its left wall
/// emitting: the right wall cannot see the left one, and every link between them that
/// refinement judges after a solve finds each visibility sample blocked. Such links are
/// dropped, not kept, yet no light goes missing: the box still absorbs what it emits
/// (within the 0.5 % of `energy_balances_in_a_closed_cube`), and no link kept carries a
/// zero factor.
#[test]
fn links_that_see_nothing_are_dropped() {
    let grey = Material::diffuse("grey", Rgb::splat(0.6));
    let lamp = Material::emitter("lamp", Rgb::splat(0.6), Rgb::splat(1.0));
    let mut scene = cube(vec![grey, lamp], [0, 0, 0, 0, 1, 0]);
    scene.polygons.push(quad(
        [[0.5, 0., 0.], [0.5, 0., 1.], [0.5, 1., 1.], [0.5, 1., 0.]],
        0,
    ));
    scene.polygons.push(quad(
        [[0.5, 0., 0.], [0.5, 1., 0.], [0.5, 1., 1.], [0.5, 0., 1.]],
        0,
    ));
    let s = solve(&scene, Params::default());
    let h = &s.hierarchy.as_ref().unwrap().hierarchy;
    assert!(h.info.invisible > 0, "{:?}", h.info);
    assert!(h.links.iter().all(|l| l.k > 0.0));
    let i = &s.info;
    let e = i.emitted.g;
    assert!((i.absorbed.g - e).abs() < 0.005 * e, "{:?}", i);
    assert!(i.escaped.g.abs() < 0.005 * e, "{:?}", i);
}

/// Parameters out of range are refused before any work.
#[test]
fn bad_parameters_are_refused() {
    for p in [
        Params {
            link_error: 0.0,
            ..Default::default()
        },
        Params {
            min_area: f64::NAN,
            ..Default::default()
        },
        Params {
            visibility_rays: 0,
            ..Default::default()
        },
        Params {
            tolerance: -1.0,
            ..Default::default()
        },
    ] {
        assert!(matches!(
            p.validate(),
            Err(HierarchicalError::Parameter { .. })
        ));
    }
}
