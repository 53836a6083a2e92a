//! Every solver against the direct (LU) solution, and the convergence facts the papers prove or
//! measure: Gauss-Seidel beats Jacobi per sweep (Szirmay-Kalos & Márton eq. 20), progressive refinement's
//! attenuation respects eq. 25, and on the random sparse systems of section 6 of Gortler et al. the
//! error after N/4 and N/2 iterations ranks overshoot ≤ progressive < gauss-seidel-0.

use radiosity::color::Rgb;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::pipeline;
use radiosity::scene::builtin;
use radiosity::solve::gauss::dense_solve;
use radiosity::solve::{relative_error, run, solve, start, Solver, SolverParams, System};
use radiosity::system::random::{reciprocal, section6, Random};
use radiosity::system::SparseMatrix;

fn max_rel_diff(a: &[Rgb], b: &[Rgb]) -> f64 {
    let scale = b.iter().map(|x| x.max_channel()).fold(0.0, f64::max);
    a.iter()
        .zip(b)
        .map(|(x, y)| x.max_abs_diff(*y))
        .fold(0.0, f64::max)
        / scale
}

fn check_all_methods(sys: &System, f: &mut SparseMatrix, what: &str) {
    let exact = dense_solve(sys, f, 1 << 32).unwrap();
    let params = SolverParams {
        tolerance: 1e-10,
        max_iterations: 50_000_000,
        ..Default::default()
    };
    // Every method but photon shooting, whose answer is random.
    for m in Solver::ALL
        .into_iter()
        .filter(|&m| m != Solver::Stochastic && m != Solver::StochasticJacobi)
    {
        let (b, info) = solve(m, sys, f, &params).unwrap();
        assert!(
            info.converged,
            "{what}: {m} did not converge ({} iterations)",
            info.iterations
        );
        let d = max_rel_diff(&b, &exact);
        assert!(d < 1e-6, "{what}: {m} differs from LU by {d:e}");
        // Energy bookkeeping: emitted = absorbed + escaped + unshot.
        let bal = info.emitted - info.absorbed - info.escaped - info.unshot;
        assert!(
            bal.max_abs_diff(Rgb::BLACK) < 1e-8 * info.emitted.max_channel(),
            "{what}: {m} energy off by {bal}"
        );
    }
}

#[test]
fn every_method_matches_lu_on_random_reciprocal_systems() {
    for (n, density, emitters, seed) in [(12, 0.6, 2, 1), (80, 0.2, 5, 2), (300, 0.05, 30, 3)] {
        let mut r = reciprocal(n, density, 0.95, (0.1, 0.9), emitters, seed);
        let (sys, f) = r.parts();
        check_all_methods(sys, f, &format!("random n={n}"));
    }
}

#[test]
fn every_method_matches_lu_on_builtin_scenes() {
    for (name, patches) in [("cube-bright", 200), ("cornell", 250), ("furnace", 150)] {
        let scene = builtin::by_name(name).unwrap();
        let mesh = Mesh::build(&scene, MeshParams::Patches(patches)).unwrap();
        let bvh = radiosity::accel::Bvh::build(&mesh);
        let mut f = radiosity::formfactor::Estimator::new(
            &mesh,
            &bvh,
            radiosity::formfactor::Params::monte_carlo(2000, 7),
        )
        .expect("valid parameters")
        .sparse_matrix();
        let data = pipeline::patch_system(&scene, &mesh);
        let sys = &data;
        check_all_methods(sys, &mut f, name);
    }
}

/// Photon shooting is unbiased with a variance that falls as 1/n: the RMS error against LU
/// shrinks by about 4 when the photons per shot grow 16×, and averaging independent runs cuts
/// it by about the square root of their number (a bias would not average away).
#[test]
fn stochastic_is_unbiased_and_error_shrinks_with_photons() {
    let mut r = reciprocal(40, 0.5, 0.9, (0.3, 0.7), 4, 11);
    let (sys, f) = r.parts();
    let exact = dense_solve(sys, f, 1 << 30).unwrap();
    let rms = |b: &[Rgb]| {
        let s: f64 = b
            .iter()
            .zip(&exact)
            .map(|(x, y)| ((x.g - y.g) / y.g).powi(2))
            .sum();
        (s / b.len() as f64).sqrt()
    };
    let mut run_once = |photons: u32, seed: u64| {
        let params = SolverParams {
            tolerance: 1e-4,
            photons,
            seed,
            ..Default::default()
        };
        let (b, info) = solve(Solver::Stochastic, sys, f, &params).unwrap();
        assert!(info.converged);
        let bal = info.emitted - info.absorbed - info.escaped - info.unshot;
        assert!(bal.max_abs_diff(Rgb::BLACK) < 1e-9 * info.emitted.max_channel());
        b
    };
    let runs = 8;
    let coarse: f64 = (1..=runs).map(|s| rms(&run_once(50, s))).sum::<f64>() / runs as f64;
    let fine_runs: Vec<Vec<Rgb>> = (1..=runs).map(|s| run_once(800, s)).collect();
    let fine: f64 = fine_runs.iter().map(|b| rms(b)).sum::<f64>() / runs as f64;
    // 16× the photons: 1/√n predicts a ratio of 4.
    assert!(
        (2.5..6.5).contains(&(coarse / fine)),
        "error {coarse} → {fine}"
    );
    let mean: Vec<Rgb> = (0..exact.len())
        .map(|i| fine_runs.iter().map(|b| b[i]).sum::<Rgb>() / runs as f64)
        .collect();
    let averaged = rms(&mean);
    // Unbiased: 1/√8 ≈ 0.35 predicted.
    assert!(
        averaged < 0.6 * fine,
        "mean of {runs} runs: {averaged} vs one run {fine}"
    );
}

fn error_after(m: Solver, r: &mut Random, iterations: u64) -> f64 {
    let (sys, f) = r.parts();
    let exact = dense_solve(sys, f, 1 << 30).unwrap();
    let params = SolverParams {
        tolerance: 0.0,
        max_iterations: iterations,
        ..Default::default()
    };
    let mut s = start(m, sys, f, &params).unwrap();
    run(&mut *s, f, &params, false, &mut |_, _| true);
    let mut b = Vec::new();
    s.radiosity(&mut b);
    relative_error(&exact, &sys.emission, &b)
}

/// Gortler et al. section 6: on random sparse 390 × 390 systems (dim and bright, few and many emitters),
/// overshooting is best, progressive refinement beats Gauss-Seidel from 0, most of all early.
#[test]
fn section6_ranking_on_random_sparse_systems() {
    let n = 390;
    for (rho, emitters, seed) in [(0.3, 5, 1), (0.8, 5, 2), (0.3, n, 3), (0.8, n, 4)] {
        let mut r = section6(n, 0.1, rho, emitters, seed);
        let mut leads = Vec::new();
        for it in [n as u64 / 4, n as u64 / 2] {
            let os = error_after(Solver::Overshoot, &mut r, it);
            let pr = error_after(Solver::Progressive, &mut r, it);
            let gs = error_after(Solver::GaussSeidel0, &mut r, it);
            let case = format!("ρ≈{rho}, {emitters} emitters, {it} iterations: overshoot {os:.4}, progressive {pr:.4}, gauss-seidel-0 {gs:.4}");
            assert!(os <= pr * 1.0001, "{case}");
            assert!(pr < gs, "{case}");
            leads.push(gs - pr);
        }
        // "Outperformed … by the greatest amounts in the early iterations": the lead, in eq. 22
        // error (the share of reflected radiosity still missing), is largest early on.
        if emitters < n {
            assert!(leads[0] > leads[1], "lead {:?}", leads);
        }
    }
}

/// Szirmay-Kalos & Márton eq. 20: Gauss-Seidel's attenuation per sweep is below Jacobi's, so from the same start
/// (B = E) its error after each full sweep is smaller.
#[test]
fn gauss_seidel_beats_jacobi_per_sweep() {
    let mut r = reciprocal(150, 0.1, 0.95, (0.5, 0.9), 10, 5);
    let n = 150u64;
    for sweeps in 1..=4 {
        let gs = error_after(Solver::GaussSeidel, &mut r, sweeps * n);
        let jac = error_after(Solver::Jacobi, &mut r, sweeps * n);
        assert!(
            gs < jac,
            "after {sweeps} sweeps: gauss-seidel {gs} vs jacobi {jac}"
        );
        assert!(gs > 0.0 && jac > 0.0);
    }
}

/// Szirmay-Kalos & Márton eq. 25: each shot of progressive refinement multiplies the unshot energy by at most
/// q* = 1 − (1 − q)/N, where q = max_j Σ_i ρ_i F_ji (the most any shooter's energy can be
/// reflected back into the unshot pool).
#[test]
fn progressive_attenuation_respects_eq25() {
    let mut r = reciprocal(100, 0.2, 0.95, (0.2, 0.9), 3, 9);
    let n = r.system.area.len();
    let q = (0..n)
        .map(|j| {
            r.f.row_entries(j)
                .iter()
                .map(|&(i, f)| r.system.reflectance[i as usize].max_channel() * f as f64)
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    assert!(q < 1.0);
    let bound = 1.0 - (1.0 - q) / n as f64;
    let (sys, f) = r.parts();
    let params = SolverParams {
        tolerance: 1e-9,
        ..Default::default()
    };
    let mut s = start(Solver::Progressive, sys, f, &params).unwrap();
    let mut last: Option<f64> = None;
    let mut worst: f64 = 0.0;
    run(&mut *s, f, &params, true, &mut |st, _| {
        if let Some(prev) = last {
            worst = worst.max(st.unshot_fraction / prev);
            assert!(
                st.unshot_fraction <= prev * bound + 1e-15,
                "step {}: {} > {prev} × {bound}",
                st.iterations,
                st.unshot_fraction
            );
        }
        last = Some(st.unshot_fraction);
        true
    });
    assert!(worst < bound);
}

/// The O(log N) shooter of progressive refinement is the linear scan's: at every shot on random
/// systems (few distinct energies are not needed: ties are settled by index in both), the
/// max-tree's choice is the first patch with the largest unshot energy |ΔB_i|₁ A_i.
#[test]
fn progressive_shooter_is_the_linear_scans() {
    use radiosity::solve::progressive::Progressive;
    use radiosity::solve::SolverState;
    for seed in 0..4 {
        let mut r = section6(300, 0.05, 0.8, 3 + seed as usize * 20, 40 + seed);
        let (sys, f) = r.parts();
        let mut p = Progressive::new(sys);
        for _ in 0..1500 {
            let energy: Vec<f64> = p
                .unshot()
                .iter()
                .zip(&sys.area)
                .map(|(u, a)| (u.r.abs() + u.g.abs() + u.b.abs()) * a)
                .collect();
            let mut scan = (0, f64::NEG_INFINITY);
            for (i, &e) in energy.iter().enumerate() {
                if e > scan.1 {
                    scan = (i, e);
                }
            }
            assert_eq!(p.shooter(), scan, "seed {seed}");
            if !p.step(f) {
                break;
            }
        }
    }
}

/// Stochastic Jacobi is unbiased with a 1/√n error, does not depend on the thread count, and
/// keeps the books, with and without the final gathering iteration: on a random reciprocal
/// system the RMS error against LU falls by about 4 when the rays per patch grow 16×; the
/// mean of independent seeds is closer to LU by about the square root of their number (a bias
/// would not average away); 1 and 2 threads give the same bits; emitted = absorbed + escaped +
/// unshot after the run; and the reported standard error has the size of the measured error.
#[test]
fn stochastic_jacobi_is_unbiased_thread_independent_and_balanced() {
    let mut r = reciprocal(60, 0.5, 0.9, (0.3, 0.7), 4, 12);
    let (sys, f) = r.parts();
    let exact = dense_solve(sys, f, 1 << 30).unwrap();
    // The measure the solver reports: area-weighted RMS of B's error over RMS of B, channels
    // summed.
    let rms = |b: &[Rgb]| {
        let (mut e, mut n) = (0.0, 0.0);
        for ((x, y), a) in b.iter().zip(&exact).zip(&sys.area) {
            e += a * (x.sum() - y.sum()).powi(2);
            n += a * y.sum().powi(2);
        }
        (e / n).sqrt()
    };
    // Gathering rays: none (the default), or as many as each iteration's.
    for gather in [false, true] {
        let mut run_once = |rays: u32, seed: u64| {
            let params = SolverParams {
                tolerance: 1e-3,
                iteration_rays: rays,
                gather_rays: if gather { rays } else { 0 },
                seed,
                ..Default::default()
            };
            let (b, info) = solve(Solver::StochasticJacobi, sys, f, &params).unwrap();
            assert!(info.converged);
            let bal = info.emitted - info.absorbed - info.escaped - info.unshot;
            assert!(
                bal.max_abs_diff(Rgb::BLACK) < 1e-9 * info.emitted.max_channel(),
                "{bal}"
            );
            assert!(info.estimated_error > 0.0);
            (b, info.estimated_error)
        };
        let runs = 8;
        let coarse: f64 = (1..=runs).map(|s| rms(&run_once(64, s).0)).sum::<f64>() / runs as f64;
        let fine_runs: Vec<(Vec<Rgb>, f64)> = (1..=runs).map(|s| run_once(1024, s)).collect();
        let fine: f64 = fine_runs.iter().map(|b| rms(&b.0)).sum::<f64>() / runs as f64;
        assert!(
            (2.5..6.5).contains(&(coarse / fine)),
            "gather {gather}: error {coarse} → {fine}"
        );
        // The reported standard error is of the measured error's size (within a factor of 3:
        // the gathering's measures the last gathering step only, the shooting's leaves out the
        // noise each iteration inherits from the one before; both have more in the measured
        // error).
        let reported = fine_runs.iter().map(|b| b.1).sum::<f64>() / runs as f64;
        assert!(
            (fine / 3.0..fine * 3.0).contains(&reported),
            "gather {gather}: reported {reported}, measured {fine}"
        );
        let mean: Vec<Rgb> = (0..exact.len())
            .map(|i| fine_runs.iter().map(|b| b.0[i]).sum::<Rgb>() / runs as f64)
            .collect();
        let averaged = rms(&mean);
        eprintln!(
            "stochastic-jacobi, gather {gather}: error {coarse:.4} → {fine:.4} (16× rays), reported {reported:.4}, mean of {runs} seeds {averaged:.4}"
        );
        // Unbiased: 1/√8 ≈ 0.35 predicted.
        assert!(
            averaged < 0.6 * fine,
            "gather {gather}: mean of {runs} runs {averaged}, one run {fine}"
        );
    }
    let mut on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                [0, 300].map(|gather_rays| {
                    let params = SolverParams {
                        tolerance: 1e-3,
                        iteration_rays: 300,
                        gather_rays,
                        seed: 9,
                        ..Default::default()
                    };
                    solve(Solver::StochasticJacobi, sys, f, &params).unwrap().0
                })
            })
    };
    assert_eq!(on(1), on(2));
}

/// Stochastic Jacobi refuses more gathering rays a patch than it may hold at once, before
/// casting any ray, naming the parameter; the most it takes is accepted.
#[test]
fn stochastic_jacobi_refuses_too_many_gathering_rays() {
    use radiosity::solve::stochastic_jacobi::{StochasticJacobi, MAX_GATHER_RAYS};
    use radiosity::solve::{Parameter, SolveError};
    let mut r = reciprocal(8, 0.5, 0.9, (0.3, 0.7), 2, 3);
    let (sys, _) = r.parts();
    let with = |gather_rays| SolverParams {
        gather_rays,
        ..Default::default()
    };
    match StochasticJacobi::new(sys, &with(MAX_GATHER_RAYS + 1)) {
        Err(SolveError::Parameter {
            parameter: Parameter::GatherRays,
            ..
        }) => {}
        other => panic!("{:?}", other.map(|_| ())),
    }
    assert!(StochasticJacobi::new(sys, &with(MAX_GATHER_RAYS)).is_ok());
}

/// A shot's receivers are updated in parallel spans when the column is long (over 512
/// entries): the residuals are bit-identical to a plain serial loop over the column with a
/// linear-scan shooter, on 1 and on 2 threads; and an operator that hands out rows for the
/// solver to apply reciprocity to (`Column::Reciprocal`) gives the bits of one that hands out
/// the columns it computed by reciprocity itself.
#[test]
fn long_shots_match_the_serial_loop_on_any_thread_count() {
    use radiosity::solve::progressive::Progressive;
    use radiosity::solve::SolverState;
    use radiosity::system::Operator;
    let shots = 40;
    let mut r = reciprocal(2000, 0.5, 0.9, (0.3, 0.8), 5, 7);
    let (sys, f) = r.parts();
    assert!(
        f.column(0, 0.0).len() > 800,
        "columns must be long enough to split"
    );
    let n = sys.len();
    let mut reference = sys.emission.clone();
    for _ in 0..shots {
        let mut best = (0, f64::NEG_INFINITY);
        for (i, r) in reference.iter().enumerate() {
            let e = (r.r.abs() + r.g.abs() + r.b.abs()) * sys.area[i];
            if e > best.1 {
                best = (i, e);
            }
        }
        let i = best.0;
        let column = f.column(i, 0.0).to_vec();
        let f_ii = column
            .iter()
            .find(|e| e.0 as usize == i)
            .map_or(0.0, |e| e.1 as f64);
        let m = Rgb::splat(1.0) - sys.reflectance[i] * f_ii;
        let ri = reference[i];
        let delta = Rgb::new(ri.r / m.r, ri.g / m.g, ri.b / m.b) * 1.0;
        reference[i] = ri - delta;
        for &(j, fj) in &column {
            let j = j as usize;
            reference[j] += sys.reflectance[j] * delta * fj as f64;
        }
    }
    let on = |threads: usize, f: &mut SparseMatrix| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut p = Progressive::new(sys);
                for _ in 0..shots {
                    assert!(p.step(f));
                }
                p.unshot().to_vec()
            })
    };
    assert_eq!(on(1, f), reference);
    assert_eq!(on(2, f), reference);

    let area = sys.area.clone();
    let mut by = |hand: Hand| {
        let mut rows = Rows {
            f: &mut *f,
            area: &area,
            hand,
            column: Vec::with_capacity(n),
            handed: 0,
        };
        let mut p = Progressive::new(sys);
        for _ in 0..shots {
            assert!(p.step(&mut rows));
        }
        p.unshot().to_vec()
    };
    assert_eq!(by(Hand::Rows), by(Hand::Columns));
}

/// The unshot energy that progressive refinement keeps as a running sum (which decides when it
/// stops) stays within a millionth of the one recomputed from the residuals, from the first
/// shots down to a unshot fraction of 10⁻¹⁰, on a system of 2,000 patches with long columns:
/// the running sums are recomputed from the residuals only when their rounding could matter.
#[test]
fn the_running_unshot_energy_matches_the_residuals() {
    use radiosity::solve::progressive::Progressive;
    use radiosity::solve::SolverState;
    let mut r = reciprocal(2000, 0.5, 0.9, (0.3, 0.8), 5, 3);
    let (sys, f) = r.parts();
    let emitted: f64 = (0..sys.len())
        .map(|i| sys.emission[i].sum() * sys.area[i])
        .sum();
    let mut p = Progressive::new(sys);
    let mut checked = 0;
    for step in 0..2_000_000u64 {
        let running = p.unshot_fraction(f, true);
        if step % 500 == 0 || running < 1e-10 {
            let exact: f64 = p
                .unshot()
                .iter()
                .zip(&sys.area)
                .map(|(r, a)| (r.r.abs() + r.g.abs() + r.b.abs()) * a)
                .sum::<f64>()
                / emitted;
            assert!(
                (running - exact).abs() <= 1e-6 * exact,
                "step {step}: running {running:e}, from the residuals {exact:e}"
            );
            checked += 1;
        }
        if running < 1e-10 || !p.step(f) {
            break;
        }
    }
    assert!(
        p.unshot_fraction(f, true) < 1e-10 && checked > 10,
        "{checked} checks"
    );
}

/// How [`Rows`] hands a shooter's column to the solver.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Hand {
    /// The column, turned by reciprocity in f32 by the operator.
    Columns,
    /// The row, for the solver to turn; the solver finds `F_ii` in it.
    Rows,
    /// The row with `F_ii` beside it, as a cache that kept it aside hands it out, with one
    /// id for every row (a stored matrix's rows never change), so that the solver keeps what
    /// it derives from a row and uses it again when that row shoots again.
    RowsWithDiagonal,
    /// As `RowsWithDiagonal`, but every row handed out has a new id: nothing kept is used.
    RowsNewIds,
}

/// Rows of a stored matrix, with columns by reciprocity in f32, handed out as [`Hand`] says.
struct Rows<'a> {
    f: &'a mut SparseMatrix,
    area: &'a [f64],
    hand: Hand,
    column: Vec<radiosity::system::Entry>,
    /// Rows handed out so far.
    handed: u64,
}

impl radiosity::system::Operator for Rows<'_> {
    fn len(&self) -> usize {
        self.area.len()
    }
    fn row(&mut self, i: usize, share: f64) -> &[radiosity::system::Entry] {
        self.f.row(i, share)
    }
    fn column(&mut self, i: usize, share: f64) -> &[radiosity::system::Entry] {
        let (area, ai) = (self.area, self.area[i] as f32);
        let row = self.f.row(i, share);
        self.column.clear();
        self.column.extend(
            row.iter()
                .map(|&(j, v)| (j, v * ai / area[j as usize] as f32)),
        );
        &self.column
    }
    fn shot_column(&mut self, i: usize, share: f64) -> radiosity::system::Column<'_> {
        use radiosity::system::Column;
        match self.hand {
            Hand::Columns => Column::Entries(self.column(i, share)),
            Hand::Rows => Column::Reciprocal {
                row: self.f.row(i, share),
                diagonal: None,
                id: None,
            },
            Hand::RowsWithDiagonal | Hand::RowsNewIds => {
                self.handed += 1;
                let id = match self.hand {
                    Hand::RowsNewIds => self.handed,
                    _ => 7,
                };
                let row = self.f.row(i, share);
                let diagonal = row.iter().find(|e| e.0 as usize == i).map_or(0.0, |e| e.1);
                Column::Reciprocal {
                    row,
                    diagonal: Some(diagonal),
                    id: Some(id),
                }
            }
        }
    }
}

/// Patches that see themselves (`F_ii` > 0, as a concave patch does): relaxing patch i divides
/// its residual by `M_ii = 1 − ρ_i F_ii` (Gortler et al. eq. 12), so that the shot, part of
/// which lands on i itself, leaves i's residual at zero; whether the operator hands out the
/// column, the row for the solver to search for `F_ii`, or the row with `F_ii` beside it (as
/// `OnDemandRows` keeps it with a cached row), that holds after the first shot, and the
/// converged answer is the same to the bit and the LU solution's. So are the energy books
/// (absorbed, escaped, unshot), whether the solver adds up each shot's receivers or uses the
/// sums it kept from the row's last shot (a row handed out again under its id).
#[test]
fn a_diagonal_handed_beside_the_row_is_the_one_searched_for() {
    use radiosity::solve::progressive::Progressive;
    use radiosity::solve::SolverState;
    let mut r = reciprocal(400, 0.2, 0.85, (0.3, 0.8), 5, 3);
    let (sys, f) = r.parts();
    // F_ii = 0.1 on every row: rows then sum to at most 0.95, and A_i F_ii is trivially
    // reciprocal.
    let rows: Vec<Vec<radiosity::system::Entry>> = (0..sys.len())
        .map(|i| {
            let mut row = f.row_entries(i).to_vec();
            let k = row.partition_point(|e| (e.0 as usize) < i);
            row.insert(k, (i as u32, 0.1));
            row
        })
        .collect();
    let mut f = SparseMatrix::from_rows(rows);
    let exact = dense_solve(sys, &mut f, 1 << 32).unwrap();
    let params = SolverParams {
        tolerance: 1e-10,
        ..Default::default()
    };
    let area = sys.area.clone();
    let mut by = |hand: Hand| {
        let mut rows = Rows {
            f: &mut f,
            area: &area,
            hand,
            column: Vec::new(),
            handed: 0,
        };
        // One shot: the shooter's own residual is zero after it (a shot divided by 1 instead
        // would leave ρ_i F_ii r_i there, a tenth of a third of it).
        let mut p = Progressive::new(sys);
        let (i, _) = p.shooter();
        let before = p.unshot()[i];
        assert!(p.step(&mut rows));
        let after = p.unshot()[i];
        assert!(
            after.max_abs_diff(Rgb::BLACK) < 1e-14 * before.max_channel(),
            "{hand:?}: shooter {i} kept {after} of {before}"
        );
        let (b, info) = solve(Solver::Progressive, sys, &mut rows, &params).unwrap();
        assert!(info.converged, "{hand:?}");
        // The solve shot each row several times: the kept sums were used.
        assert!(info.iterations > 2 * sys.len() as u64, "{hand:?}");
        (b, [info.absorbed, info.escaped, info.unshot])
    };
    let (searched, books) = by(Hand::Rows);
    assert_eq!(by(Hand::RowsWithDiagonal), (searched.clone(), books));
    assert_eq!(by(Hand::RowsNewIds), (searched.clone(), books));
    assert_eq!(by(Hand::Columns), (searched.clone(), books));
    // The criterion every method meets against LU at this tolerance (`check_all_methods`).
    let err = max_rel_diff(&searched, &exact);
    assert!(err < 1e-6, "progressive against LU: {err:e}");
}

/// On a worker of a pool of two or three threads, `run` keeps the other workers awake while it
/// solves (`KeepAwake`): the result is bit for bit the one off the pool and on one thread, for
/// a shooting method and for a sweeping one, and the pool is free for other work afterwards.
#[test]
fn solves_on_a_worker_match_solves_off_the_pool() {
    // Rows of about 800 entries: a shot halves its receivers (spans of over 512) and, with a
    // second thread free, updates the halves at once; the energy sums are added by the same
    // halving either way.
    let mut r = section6(2000, 0.4, 0.8, 20, 11);
    let (sys, f) = r.parts();
    for method in [Solver::Progressive, Solver::GaussSeidel] {
        let params = SolverParams {
            tolerance: 1e-6,
            ..Default::default()
        };
        let off = solve(method, sys, f, &params).unwrap();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let on = pool.install(|| solve(method, sys, f, &params).unwrap());
            assert_eq!(on.0, off.0, "{method:?} on {threads} threads");
            assert_eq!(on.1.iterations, off.1.iterations);
            let books = |i: &radiosity::solve::Info| {
                (i.absorbed, i.escaped, i.unshot, i.unshot_fraction.to_bits())
            };
            assert_eq!(
                books(&on.1),
                books(&off.1),
                "{method:?} on {threads} threads"
            );
            let sum: u64 = pool.install(|| {
                use rayon::prelude::*;
                (0..10_000u64).into_par_iter().sum()
            });
            assert_eq!(sum, 49_995_000);
        }
    }
}
