use radiosity::pipeline::{solve, Settings};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let scene = radiosity::scene::load_with(&path, &Default::default()).unwrap();
    let mut s2 = Settings::default();
    let le: f64 = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(1e-5);
    s2.hierarchical = Some(radiosity::hierarchical::Params { link_error: le, ..Default::default() });
    let sol = solve(&scene, &s2, &radiosity::observe::Silent).unwrap();
    let hs = sol.hierarchy.as_ref().unwrap();
    let h = &hs.hierarchy;
    let n = h.elements.items.len();
    let mut own = vec![0.0f64; n];
    let mut own_cl = vec![0.0f64; n];
    for l in &h.links { own[l.receiver as usize] += l.k as f64; if l.source & (1<<31) != 0 { own_cl[l.receiver as usize] += l.k as f64; } }
    let mut tot = vec![0.0f64; n];
    let mut totc = vec![0.0f64; n];
    for e in 0..n { let p = h.elements.items[e].parent; tot[e] = own[e] + if p == u32::MAX {0.0} else {tot[p as usize]}; totc[e] = own_cl[e] + if p == u32::MAX {0.0} else {totc[p as usize]}; }
    let (mut sa, mut a, mut sc) = (0.0, 0.0, 0.0);
    let mut by_level = std::collections::BTreeMap::new();
    for &l in &hs.leaves { let el = &h.elements.items[l as usize]; let w = el.area as f64; sa += w * tot[l as usize]; sc += w*totc[l as usize]; a += w; let e = by_level.entry(el.level).or_insert((0.0,0.0,0)); e.0 += w*tot[l as usize]; e.1 += w; e.2 += 1; }
    println!("area-weighted row sum {} (clusters {}) over {} leaves", sa / a, sc/a, hs.leaves.len());
    for (lv, (s, w, c)) in by_level { println!("level {lv}: {} ({c})", s / w); }
}
