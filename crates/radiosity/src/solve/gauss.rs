//! Gauss elimination (Szirmay-Kalos & Márton (1995), "Solution of the linear equation"): the dense
//! matrix `M = I − diag(ρ) F` is built and factored by LU with partial pivoting (faer), once
//! per distinct reflectance channel (once in all when ρ is grey), and solved for the three
//! channels of E. O(N³) time and O(N²) memory: it is refused, with the alternative named, when
//! the dense matrix would not fit in the memory limit. It is also the reference solution that
//! the iterative methods are measured against.

use super::{Info, Operator, SolveError, Solver, SolverParams, SolverState, System};
use crate::color::Rgb;
use crate::system::{balance, Entry, SparseMatrix};
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Bytes the dense solve needs for N unknowns (the matrix and its factorisation).
pub fn bytes_needed(n: usize) -> u64 {
    2 * 8 * (n as u64) * (n as u64)
}

/// Solve `system` exactly (to rounding) by dense LU, if it fits in `limit` bytes.
pub fn dense_solve(
    system: &System,
    source: &mut dyn Operator,
    limit: u64,
) -> Result<Vec<Rgb>, SolveError> {
    let rows: Vec<Vec<Entry>> = (0..system.len())
        .map(|i| source.row(i, 0.0).to_vec())
        .collect();
    solve_rows(system, |i| &rows[i], limit)
}

/// [`dense_solve`] with a stored matrix.
pub fn dense_solve_matrix(
    system: &System,
    m: &SparseMatrix,
    limit: u64,
) -> Result<Vec<Rgb>, SolveError> {
    solve_rows(system, |i| m.row_entries(i), limit)
}

fn solve_rows<'m>(
    system: &System,
    row: impl Fn(usize) -> &'m [Entry],
    limit: u64,
) -> Result<Vec<Rgb>, SolveError> {
    let n = system.len();
    let needed = bytes_needed(n);
    if needed > limit {
        return Err(SolveError::TooLarge {
            solver: Solver::Gauss,
            n,
            needed,
            limit,
            alternative:
                "an iterative solver (progressive, gauss-seidel or overshoot) needs no dense matrix",
        });
    }
    let grey = system.reflectance.iter().all(|r| r.r == r.g && r.g == r.b);
    let channels: &[usize] = if grey { &[0] } else { &[0, 1, 2] };
    let mut out = vec![Rgb::BLACK; n];
    for &c in channels {
        let rho = |i: usize| system.reflectance[i].to_array()[c];
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            m[(i, i)] += 1.0;
            for &(j, f) in row(i) {
                m[(i, j as usize)] -= rho(i) * f as f64;
            }
        }
        let rhs_channels: Vec<usize> = if grey { vec![0, 1, 2] } else { vec![c] };
        let rhs = Mat::<f64>::from_fn(n, rhs_channels.len(), |i, k| {
            system.emission[i].to_array()[rhs_channels[k]]
        });
        let lu = m.partial_piv_lu();
        let x = lu.solve(&rhs);
        for i in 0..n {
            let mut v = out[i].to_array();
            for (k, &ch) in rhs_channels.iter().enumerate() {
                v[ch] = x[(i, k)];
            }
            out[i] = Rgb::from_array(v);
        }
    }
    if out.iter().any(|b| !b.is_finite()) {
        return Err(SolveError::Singular);
    }
    Ok(out)
}

/// Gauss elimination as a one-step solver.
#[derive(Clone, Debug)]
pub struct Gauss<'s> {
    system: &'s System,
    b: Option<Vec<Rgb>>,
    limit: u64,
}

impl<'s> Gauss<'s> {
    /// Prepare; refuses at once if the dense matrix would not fit.
    pub fn new(system: &'s System, params: &SolverParams) -> Result<Self, SolveError> {
        let needed = bytes_needed(system.len());
        if needed > params.memory_limit {
            return Err(SolveError::TooLarge {
                solver: Solver::Gauss,
                n: system.len(),
                needed,
                limit: params.memory_limit,
                alternative: "an iterative solver (progressive, gauss-seidel or overshoot) needs no dense matrix",
            });
        }
        Ok(Self {
            system,
            b: None,
            limit: params.memory_limit,
        })
    }
}

impl SolverState for Gauss<'_> {
    fn method(&self) -> Solver {
        Solver::Gauss
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        if self.b.is_none() {
            // `new` checked the size, so only a singular matrix can fail here; then keep E.
            self.b = Some(
                dense_solve(self.system, source, self.limit)
                    .unwrap_or_else(|_| self.system.emission.to_vec()),
            );
        }
        false
    }

    fn radiosity(&self, out: &mut Vec<Rgb>) {
        out.clear();
        match &self.b {
            Some(b) => out.extend_from_slice(b),
            None => out.resize(self.system.len(), Rgb::BLACK),
        }
    }

    fn unshot_fraction(&mut self, source: &mut dyn Operator, _: bool) -> f64 {
        match &self.b {
            None => 1.0,
            Some(b) => balance(self.system, source, b).3 / self.system.emitted_power().sum(),
        }
    }

    fn iterations(&self) -> u64 {
        self.b.is_some() as u64
    }

    fn info(&mut self, source: &mut dyn Operator) -> Info {
        let mut b = Vec::new();
        self.radiosity(&mut b);
        let (absorbed, escaped, unshot, abs) = balance(self.system, source, &b);
        let emitted = self.system.emitted_power();
        Info {
            iterations: self.iterations(),
            converged: false,
            unshot_fraction: abs / emitted.sum(),
            seconds: 0.0,
            emitted,
            absorbed,
            escaped,
            unshot,
            estimated_error: 0.0,
            ray_seconds: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{start, Solver};

    #[test]
    fn refuses_a_dense_matrix_beyond_the_limit_and_names_the_alternative() {
        let n = 1000;
        let area = vec![1.0; n];
        let refl = vec![Rgb::splat(0.5); n];
        let mut emis = vec![Rgb::BLACK; n];
        emis[0] = Rgb::splat(1.0);
        let sys = System {
            area: area.to_vec(),
            reflectance: refl.to_vec(),
            emission: emis.to_vec(),
        };
        let mut f = SparseMatrix::from_rows(vec![Vec::new(); n]);
        let params = SolverParams {
            memory_limit: bytes_needed(n) - 1,
            ..Default::default()
        };
        let err = start(Solver::Gauss, &sys, &mut f, &params)
            .err()
            .expect("refused");
        let msg = err.to_string();
        assert!(
            msg.contains("gauss") && msg.contains("progressive"),
            "{msg}"
        );
        // At the limit it runs, and with F = 0 the answer is B = E.
        let params = SolverParams {
            memory_limit: bytes_needed(n),
            ..Default::default()
        };
        let (b, _) = crate::solve::solve(Solver::Gauss, &sys, &mut f, &params).unwrap();
        assert_eq!(b, emis);
    }
}
