use radiosity::pipeline::{solve, Settings};
use radiosity::scene::builtin;
use radiosity::Rgb;
fn main() {
    let mut scene = builtin::by_name("cornell").unwrap();
    let list: Vec<usize> = std::env::args().skip(1).map(|s| s.parse().unwrap()).collect();
    for m in scene.materials.iter_mut() { m.reflectance = Rgb::BLACK; }
    let mut m = scene.materials[0].clone();
    m.name = "test".into();
    m.reflectance = Rgb::splat(0.5);
    m.emission = Rgb::BLACK;
    scene.materials.push(m);
    let k = scene.materials.len() - 1;
    for &w in &list { scene.polygons[w].material = k; }
    let mut s1 = Settings::default();
    s1.params.tolerance = 1e-6;
    s1.form_factors.rays = 4096;
    s1.mesh = radiosity::mesh::MeshParams::Patches(4000);
    let u = solve(&scene, &s1, &radiosity::observe::Silent).unwrap();
    let mut s2 = Settings::default();
    s2.hierarchical = Some(radiosity::hierarchical::Params { link_error: 1e-5, tolerance: 1e-6, ..Default::default()});
    let h = solve(&scene, &s2, &radiosity::observe::Silent).unwrap();
    let mean = |s: &radiosity::pipeline::Solution, which: usize| {
        let (mut a, mut b) = (0.0, 0.0);
        for (p, r) in s.mesh.patches.iter().zip(&s.radiosity) {
            if p.surface as usize == which { a += p.area as f64; b += p.area as f64 * r.g; }
        }
        b / a
    };
    for &w in &list { println!("surface {w}: uniform {:.5} hierarchical {:.5} {:+.2}%", mean(&u, w), mean(&h, w), 100.0*(mean(&h,w)/mean(&u,w)-1.0)); }
}
