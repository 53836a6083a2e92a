//! `radiosity bench --scale SCENE --sizes N,N,… --bookkeeping`: a shooting method's own work
//! without its form factors. Each size is solved once, which fills the row cache, and then
//! `--runs` more times from the start on the cached rows, no rays: every shot then finds the
//! row its patch last computed, so these solves are alike (and close to the first). What those solves take is the method's bookkeeping alone (choosing the
//! shooter, updating the receivers, keeping the books), free of the rays' noise, which at 10⁵
//! patches and more is five to ten times larger.

use crate::args::ScaleArgs;
use anyhow::{bail, Context, Result};
use radiosity::formfactor::{Estimator, OnDemandRows, Params as FormFactorParams};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::solve::{Operator, Solver, SolverParams};
use radiosity::system::{Column, Entry, PhotonSampler};
use radiosity::Rgb;
use std::time::Instant;

/// The rows, counting the column entries the solver is handed: the receivers it
/// updates.
struct Counting<'a, 'b> {
    rows: &'b mut OnDemandRows<'a>,
    entries: u64,
}

impl Operator for Counting<'_, '_> {
    fn len(&self) -> usize {
        self.rows.len()
    }
    fn row(&mut self, i: usize, share: f64) -> &[Entry] {
        let row = self.rows.row(i, share);
        self.entries += row.len() as u64;
        row
    }
    fn column(&mut self, i: usize, share: f64) -> &[Entry] {
        let column = self.rows.column(i, share);
        self.entries += column.len() as u64;
        column
    }
    fn shot_column(&mut self, i: usize, share: f64) -> Column<'_> {
        let column = self.rows.shot_column(i, share);
        self.entries += column.entries().len() as u64;
        column
    }
    fn apply(&mut self, x: &[Rgb], y: &mut [Rgb]) {
        self.rows.apply(x, y);
    }
    fn apply_transpose(&mut self, x: &[Rgb], y: &mut [Rgb]) {
        self.rows.apply_transpose(x, y);
    }
    fn photons(&self) -> Option<&dyn PhotonSampler> {
        None
    }
}

/// Run the bookkeeping benchmark.
pub fn run(a: &ScaleArgs) -> Result<()> {
    crate::positive(&[("--runs", a.runs)])?;
    let (scene, sizes) = (a.scene.as_str(), &a.sizes);
    let method = a.solve.solver.0;
    if matches!(
        method,
        Solver::Gauss | Solver::Stochastic | Solver::StochasticJacobi
    ) {
        bail!(
            "--bookkeeping: {} does not shoot or gather cached rows; use progressive, southwell, overshoot, overshoot-ambient or a gathering method",
            method.name()
        );
    }
    let scene_data = radiosity_cli::load_scene(scene, a.solve.one_sided)?;
    let limit = radiosity::pipeline::available_memory().unwrap_or(8 << 30);
    println!(
        "bookkeeping: {scene}, {} to {:.2}% unshot, {} threads; each size solved once to fill the row cache, then {} more times on the cached rows (the median is reported)",
        method.name(),
        100.0 * a.solve.tolerance,
        rayon::current_num_threads(),
        a.runs
    );
    println!(
        "{:>9} {:>9} {:>13} {:>9} {:>10} {:>10} {:>11}",
        "patches", "shots", "updates", "rows", "first s", "cached s", "ns/update"
    );
    let ff = FormFactorParams::shooting();
    let memory = radiosity::pipeline::MemoryCheck {
        limit,
        stored_rows: false,
        rays: ff.rays,
    };
    for &n in sizes {
        // As `solve` does: the patches' memory is checked before meshing, and the row cache
        // gets half of what is left.
        memory.before_meshing(&scene_data, MeshParams::Patches(n))?;
        let mesh = Mesh::build(&scene_data, MeshParams::Patches(n))?;
        let needed = memory.check(mesh.len() as u64)?;
        let bvh = radiosity::accel::Bvh::build(&mesh);
        let system = radiosity::mesh::patch_system(&scene_data, &mesh);
        system.validate().context("the scene's patch system")?;
        let ff = FormFactorParams {
            cache_bytes: ((limit - needed) / 2) as usize,
            ..ff
        };
        let estimator = Estimator::new(&mesh, &bvh, ff)?;
        let mut rows = OnDemandRows::new(estimator);
        let params = SolverParams {
            tolerance: a.solve.tolerance,
            ..Default::default()
        };
        let mut times = Vec::new();
        let mut shots = 0;
        let mut updates = 0;
        let mut computed = 0;
        for round in 0..=a.runs {
            let mut source = Counting {
                rows: &mut rows,
                entries: 0,
            };
            let t = Instant::now();
            let info = radiosity_cli::settings::on_worker(|| -> Result<_> {
                let mut s = radiosity::solve::start(method, &system, &mut source, &params)?;
                Ok(radiosity::solve::run(
                    &mut *s,
                    &mut source,
                    &params,
                    false,
                    &mut |_, _| true,
                ))
            })?;
            times.push(t.elapsed().as_secs_f64());
            (shots, updates) = (info.iterations, source.entries);
            if round == 0 {
                computed = rows.stats().rows;
            } else if rows.stats().rows != computed {
                bail!(
                    "{n} patches: a solve on the cached rows had to compute {} rows: the cache did not hold them all (too little memory?)",
                    rows.stats().rows - computed
                );
            }
        }
        let first = times[0];
        let mut cached = times[1..].to_vec();
        cached.sort_by(f64::total_cmp);
        let median = cached[cached.len() / 2];
        println!(
            "{:>9} {:>9} {:>13} {:>9} {:>10.2} {:>10.3} {:>11.2}",
            mesh.len(),
            shots,
            updates,
            computed,
            first,
            median,
            median * 1e9 / updates.max(1) as f64
        );
    }
    Ok(())
}
