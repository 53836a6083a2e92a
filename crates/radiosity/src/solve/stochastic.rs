//! Probabilistic progressive refinement (Szirmay-Kalos & Márton (1995), "Probabilistic progressive
//! refinement"): B and the unshot radiosity U start at E. Each iteration takes the patch j with
//! the most unshot energy `U_j A_j` and sends one photon carrying `1/n` of that power: it leaves
//! from a uniform point of j in a cosine-distributed direction, i.e. it lands on patch k with
//! probability `F_jk` ([`crate::system::PhotonSampler::sample`]: a ray on a scene, a draw from row j of a stored
//! matrix). Patch k keeps `ρ_k` of the power as new unshot and total radiosity; `U_j` loses
//! `U_j/n`. No form factor is stored. The result is unbiased; its variance falls as n grows.
//! Shooters are found in O(log N) with a max-tree over the unshot energies.

use super::select::MaxTree;
use super::{Info, Operator, SolveError, Solver, SolverParams, SolverState, System};
use crate::color::Rgb;
use crate::sampling::{stream, Rng64};

/// Photon shooting in progress.
#[derive(Clone, Debug)]
pub struct Stochastic<'s> {
    system: &'s System,
    b: Vec<Rgb>,
    u: Vec<Rgb>,
    tree: MaxTree,
    rng: Rng64,
    photons: f64,
    emitted: Rgb,
    emitted_total: f64,
    absorbed: Rgb,
    escaped: Rgb,
    iterations: u64,
    /// Σ U_i A_i kept up to date by each photon (O(1)), so that the stopping test does not
    /// cost O(N) per photon; recomputed exactly on request.
    unshot_running: Rgb,
}

fn energy(u: Rgb, a: f64) -> f64 {
    (u.r + u.g + u.b) * a
}

impl<'s> Stochastic<'s> {
    /// Start: B = U = E; photons carry `1/params.photons` of the shooter's unshot power.
    pub fn new(system: &'s System, params: &SolverParams) -> Result<Self, SolveError> {
        if params.photons == 0 {
            return Err(SolveError::Parameter {
                parameter: super::Parameter::Photons,
                value: 0.0,
                range: "[1, 2³²)",
            });
        }
        let keys: Vec<f64> = (0..system.len())
            .map(|i| energy(system.emission[i], system.area[i]))
            .collect();
        let emitted = system.emitted_power();
        Ok(Self {
            b: system.emission.to_vec(),
            u: system.emission.to_vec(),
            tree: MaxTree::new(&keys),
            rng: stream(params.seed, 0x5354_4f43, 0, 0),
            photons: params.photons as f64,
            emitted,
            emitted_total: emitted.sum(),
            absorbed: Rgb::BLACK,
            escaped: Rgb::BLACK,
            iterations: 0,
            unshot_running: emitted,
            system,
        })
    }

    fn unshot_power(&self) -> Rgb {
        self.u
            .iter()
            .zip(&self.system.area)
            .map(|(u, a)| *u * *a)
            .sum()
    }
}

impl SolverState for Stochastic<'_> {
    fn method(&self) -> Solver {
        Solver::Stochastic
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        let (key, j) = self.tree.max();
        if key <= 0.0 {
            return false;
        }
        let sys = self.system;
        let power = self.u[j] * (sys.area[j] / self.photons);
        let uj = self.u[j];
        self.u[j] = uj - uj / self.photons;
        self.tree.set(j, energy(self.u[j], sys.area[j]));
        self.unshot_running -= power;
        match source
            .photons()
            .expect("checked by solve::start")
            .sample(j, &mut self.rng)
        {
            Some(k) => {
                let k = k as usize;
                let rho = sys.reflectance[k];
                let db = rho * power / sys.area[k];
                self.u[k] += db;
                self.b[k] += db;
                self.absorbed += (Rgb::splat(1.0) - rho) * power;
                self.unshot_running += rho * power;
                self.tree.set(k, energy(self.u[k], sys.area[k]));
            }
            None => self.escaped += power,
        }
        self.iterations += 1;
        true
    }

    fn radiosity(&self, out: &mut Vec<Rgb>) {
        out.clear();
        out.extend_from_slice(&self.b);
    }

    fn unshot(&self) -> Option<std::borrow::Cow<'_, [Rgb]>> {
        Some(std::borrow::Cow::Borrowed(&self.u))
    }

    fn unshot_fraction(&mut self, _: &mut dyn Operator, exact: bool) -> f64 {
        if exact {
            self.unshot_running = self.unshot_power();
        }
        self.unshot_running.map(|v| v.max(0.0)).sum() / self.emitted_total
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn info(&mut self, _: &mut dyn Operator) -> Info {
        let unshot = self.unshot_power();
        Info {
            iterations: self.iterations,
            converged: false,
            unshot_fraction: unshot.sum() / self.emitted_total,
            seconds: 0.0,
            emitted: self.emitted,
            absorbed: self.absorbed,
            escaped: self.escaped,
            unshot,
            estimated_error: 0.0,
            ray_seconds: 0.0,
        }
    }
}
