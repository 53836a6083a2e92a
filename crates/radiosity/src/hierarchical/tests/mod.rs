//! Tests of the hierarchical solver, by topic, and the scenes and solves they share.

use super::*;
use crate::geom::Vec3;
use crate::pipeline::{self, Settings};
use crate::scene::{Material, Polygon, Scene};

mod cover;
mod links;
mod refinement;
mod solution;

fn quad(v: [[f32; 3]; 4], material: usize) -> Polygon {
    Polygon {
        vertices: v.iter().map(|p| Vec3::from_array(*p)).collect(),
        material,
        line: 0,
        group: 0,
    }
}

/// A closed unit cube seen from inside: floor, ceiling and four walls, with the given
/// material per face.
fn cube(materials: Vec<Material>, of_face: [usize; 6]) -> Scene {
    let faces = [
        [[0., 0., 0.], [0., 0., 1.], [1., 0., 1.], [1., 0., 0.]],
        [[0., 1., 0.], [1., 1., 0.], [1., 1., 1.], [0., 1., 1.]],
        [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
        [[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]],
        [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]],
        [[1., 0., 0.], [1., 0., 1.], [1., 1., 1.], [1., 1., 0.]],
    ];
    Scene {
        name: "cube".into(),
        materials,
        polygons: (0..6).map(|k| quad(faces[k], of_face[k])).collect(),
        ..Scene::default()
    }
}

/// The exact system of a solution's leaves (analytic factors, no occlusion) solved by LU.
fn exact_leaf_solution(s: &pipeline::Solution) -> pipeline::SystemSolution {
    let ff =
        crate::formfactor::Params::geometric(crate::formfactor::FormFactorMethod::Analytic, 2, 1);
    let est = crate::formfactor::Estimator::new(&s.mesh, &s.bvh, ff).unwrap();
    let mut f = est
        .matrix(crate::formfactor::Storage::Sparse, &crate::observe::Silent)
        .into_sparse();
    pipeline::solve_system(
        &s.system,
        &mut f,
        crate::solve::Solver::Gauss,
        &Default::default(),
        false,
        &crate::observe::Silent,
    )
    .unwrap()
}

fn solve(scene: &Scene, params: Params) -> pipeline::Solution {
    let settings = Settings::from(params);
    pipeline::solve(scene, &settings, &crate::observe::Silent).unwrap()
}
