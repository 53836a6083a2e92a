//! Overshooting by SuperShootGather (Gortler, Cohen & Slusallek (1993) section 2.2.2 and appendix C).
//!
//! When patch i is chosen, its row and its column of F are both known (reciprocity, eq. 3),
//! so it can shoot, gather, shoot again and so on *ad infinitum* in closed form. That solves
//! the sub-problem where i interacts with every patch and the others not with each other
//! (eq. 4–5):
//!
//! ```text
//! (SG)_i = Σ_{j≠i} ρ_i F_ij ΔB_ji / (1 − Σ_{j≠i} ρ_i F_ij ρ_j F_ji)
//! (SG)_j = ΔB_ji + ρ_j F_ji (SG)_i
//! ```
//!
//! The amount left to shoot now depends on the pair: `ΔB_jk = B_j − ∇B_jk`, where `∇B_jk` is
//! the radiosity already shot from j to k. `∇B` is non-zero only in the rows and columns of
//! patches already chosen, and only those are stored: O(N) per chosen patch, O(N) work per
//! step. A step, following the paper's pseudo-code:
//! 1. shoot: `B_j += ρ_j F_ji ΔB_ij` for every j, then `∇B_ij = B_i`;
//! 2. gather in closed form: `B_i += (SG)_i`; `B_j += ρ_j F_ji (SG)_i`; then `∇B_ji = B_j`
//!    and `∇B_ij = B_i` for every j.
//!
//! The chosen patch is the one with the most radiosity received since it last shot, weighted
//! by area. This approximates the paper's "row and column of unshot radiosity" (a column sum
//! differs between patches only for those already chosen). Patches must not see themselves
//! (F_ii = 0, true of planar patches). The residual is not kept: it is recomputed from every
//! row of F, every N/8 steps for the stopping test, and at every step when a trace asks.

use super::select::MaxTree;
use super::{Info, Operator, SolveError, Solver, SolverParams, SolverState, System};
use crate::color::Rgb;
use crate::system::balance;
use crate::system::Entry;

const NONE: u32 = u32::MAX;

/// The shooter's key: radiosity received since the last shot, `|b − last|₁ · A`.
fn key(b: Rgb, last: Rgb, area: f64) -> f64 {
    let d = b - last;
    (d.r.abs() + d.g.abs() + d.b.abs()) * area
}

/// SuperShootGather in progress.
#[derive(Clone, Debug)]
pub struct Overshoot<'s> {
    system: &'s System,
    b: Vec<Rgb>,
    /// B_i when i was last chosen (zero before).
    last: Vec<Rgb>,
    /// `|B_k − last_k|₁ A_k`, the radiosity received since k last shot, as energy: the
    /// shooter is its arg-max ([`super::select`]).
    tree: MaxTree,
    slot: Vec<u32>,
    chosen: Vec<u32>,
    /// `shot_from[slot(c)][k] = ∇B_ck`.
    shot_from: Vec<Vec<Rgb>>,
    /// `shot_to[slot(c)][j] = ∇B_jc`.
    shot_to: Vec<Vec<Rgb>>,
    column: Vec<Entry>,
    row: Vec<Entry>,
    iterations: u64,
    unshot: f64,
    checked_at: u64,
    emitted_total: f64,
    limit: u64,
}

impl<'s> Overshoot<'s> {
    /// Start from B = E (nothing shot). Refuses systems with F_ii ≠ 0, and systems whose shot
    /// matrix could outgrow `params.memory_limit`.
    pub fn new(
        system: &'s System,
        source: &mut dyn Operator,
        params: &SolverParams,
    ) -> Result<Self, SolveError> {
        let n = system.len();
        for i in 0..n {
            if let Some(e) = source
                .row(i, 0.0)
                .iter()
                .find(|e| e.0 as usize == i && e.1 != 0.0)
            {
                return Err(SolveError::SelfFactor {
                    solver: Solver::Overshoot,
                    patch: i,
                    value: e.1,
                });
            }
        }
        let most_chosen = (n as u64).min(params.max_iterations);
        let needed = most_chosen * n as u64 * 2 * std::mem::size_of::<Rgb>() as u64;
        if needed > params.memory_limit {
            return Err(SolveError::TooLarge {
                solver: Solver::Overshoot,
                n,
                needed,
                limit: params.memory_limit,
                alternative:
                    "progressive or overshoot-ambient need O(N) memory, or allow fewer iterations",
            });
        }
        Ok(Self {
            b: system.emission.to_vec(),
            last: vec![Rgb::BLACK; n],
            tree: MaxTree::new(
                &(0..n)
                    .map(|k| key(system.emission[k], Rgb::BLACK, system.area[k]))
                    .collect::<Vec<_>>(),
            ),
            slot: vec![NONE; n],
            chosen: Vec::new(),
            shot_from: Vec::new(),
            shot_to: Vec::new(),
            column: Vec::new(),
            row: Vec::new(),
            iterations: 0,
            unshot: 1.0,
            checked_at: u64::MAX,
            emitted_total: system.emitted_power().sum(),
            limit: params.memory_limit,
            system,
        })
    }

    /// `∇B_jk`, the radiosity already shot from j to k.
    fn shot(&self, j: usize, k: usize) -> Rgb {
        if self.slot[j] != NONE {
            self.shot_from[self.slot[j] as usize][k]
        } else if self.slot[k] != NONE {
            self.shot_to[self.slot[k] as usize][j]
        } else {
            Rgb::BLACK
        }
    }

    /// Give `i` a stored row and column (copying what the other stores hold for it).
    fn choose(&mut self, i: usize) -> usize {
        if self.slot[i] != NONE {
            return self.slot[i] as usize;
        }
        let n = self.b.len();
        let from: Vec<Rgb> = (0..n).map(|k| self.shot(i, k)).collect();
        let to: Vec<Rgb> = (0..n).map(|j| self.shot(j, i)).collect();
        self.slot[i] = self.chosen.len() as u32;
        self.chosen.push(i as u32);
        self.shot_from.push(from);
        self.shot_to.push(to);
        self.chosen.len() - 1
    }

    /// `∇B_ik = B_i` for every k (i has shot everything it has to everyone).
    fn mark_shot_from(&mut self, i: usize, s: usize) {
        let bi = self.b[i];
        self.shot_from[s].iter_mut().for_each(|v| *v = bi);
        for (c, &p) in self.chosen.iter().enumerate() {
            self.shot_to[c][i] = if p as usize == i {
                self.shot_to[c][i]
            } else {
                bi
            };
        }
    }

    /// `∇B_ji = B_j` for every j (i has gathered everything everyone had for it).
    fn mark_shot_to(&mut self, i: usize, s: usize) {
        for j in 0..self.b.len() {
            self.shot_to[s][j] = self.b[j];
        }
        for (c, &p) in self.chosen.iter().enumerate() {
            if p as usize != i {
                self.shot_from[c][i] = self.b[p as usize];
            }
        }
    }

    fn bytes(&self) -> u64 {
        (self.chosen.len() * self.b.len() * 2 * std::mem::size_of::<Rgb>()) as u64
    }
}

impl SolverState for Overshoot<'_> {
    fn method(&self) -> Solver {
        Solver::Overshoot
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        let sys = self.system;
        let (best, i) = self.tree.max();
        if best <= 0.0 || self.bytes() > self.limit {
            return false;
        }
        let share = best / self.emitted_total;
        self.column.clear();
        self.column.extend_from_slice(source.column(i, share));
        self.row.clear();
        self.row.extend_from_slice(source.row(i, share));
        let s = self.choose(i);

        // 1. Shoot what i has not yet shot to each j.
        for &(j, f) in &self.column {
            let j = j as usize;
            if j != i {
                let unshot = self.b[i] - self.shot_from[s][j];
                self.b[j] += sys.reflectance[j] * unshot * f as f64;
            }
        }
        self.mark_shot_from(i, s);

        // 2. SuperShootGather: numerator from row i, denominator from row i and column i.
        let rho_i = sys.reflectance[i];
        let mut num = Rgb::BLACK;
        let mut loop_gain = Rgb::BLACK;
        let mut c = 0;
        for &(j, f_ij) in &self.row {
            let ju = j as usize;
            if ju == i {
                continue;
            }
            num += rho_i * (self.b[ju] - self.shot_to[s][ju]) * f_ij as f64;
            while c < self.column.len() && self.column[c].0 < j {
                c += 1;
            }
            if c < self.column.len() && self.column[c].0 == j {
                let f_ji = self.column[c].1 as f64;
                loop_gain += rho_i * sys.reflectance[ju] * (f_ij as f64 * f_ji);
            }
        }
        let den = Rgb::splat(1.0) - loop_gain;
        let sg = Rgb::new(num.r / den.r, num.g / den.g, num.b / den.b);
        self.b[i] += sg;
        for &(j, f) in &self.column {
            let j = j as usize;
            if j != i {
                self.b[j] += sys.reflectance[j] * sg * f as f64;
            }
        }
        self.mark_shot_to(i, s);
        self.mark_shot_from(i, s);
        self.last[i] = self.b[i];
        // Only i and the receivers in column i changed.
        self.tree.set(i, key(self.b[i], self.last[i], sys.area[i]));
        for &(j, _) in &self.column {
            let j = j as usize;
            self.tree.set(j, key(self.b[j], self.last[j], sys.area[j]));
        }
        self.iterations += 1;
        true
    }

    fn radiosity(&self, out: &mut Vec<Rgb>) {
        out.clear();
        out.extend_from_slice(&self.b);
    }

    fn unshot_fraction(&mut self, source: &mut dyn Operator, exact: bool) -> f64 {
        let interval = (self.b.len() as u64 / 8).max(1);
        if exact || self.checked_at == u64::MAX || self.iterations >= self.checked_at + interval {
            let (_, _, _, abs) = balance(self.system, source, &self.b);
            self.unshot = abs / self.emitted_total;
            self.checked_at = self.iterations;
        }
        self.unshot
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn info(&mut self, source: &mut dyn Operator) -> Info {
        let (absorbed, escaped, unshot, abs) = balance(self.system, source, &self.b);
        Info {
            iterations: self.iterations,
            converged: false,
            unshot_fraction: abs / self.emitted_total,
            seconds: 0.0,
            emitted: self.system.emitted_power(),
            absorbed,
            escaped,
            unshot,
            estimated_error: 0.0,
            ray_seconds: 0.0,
        }
    }
}
