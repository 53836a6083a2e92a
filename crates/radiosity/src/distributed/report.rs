//! What a distributed run did ([`Report`]: blocks, traffic, balance, sweeps), the same on every
//! rank, and which methods run over ranks.

use crate::comm::{Ranks, Traffic};
use crate::solve::Solver;
use crate::Error;
use std::ops::Range;

/// The methods that run over several ranks.
pub const DISTRIBUTED_SOLVERS: [Solver; 2] = [Solver::Jacobi, Solver::StochasticJacobi];

/// What a distributed run did, the same on every rank.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// The transport ([`super::Communicator::describe`]).
    pub transport: String,
    /// Each rank's block of patches (rows of F, or the patches whose rays it gathers).
    pub blocks: Vec<Range<usize>>,
    /// Seconds estimating row costs (Jacobi's pilot).
    pub pilot_seconds: f64,
    /// Per rank: seconds of its own work (rows of F, sweeps, rays), without waiting.
    pub busy: Vec<f64>,
    /// Per rank: its traffic.
    pub traffic: Vec<Traffic>,
    /// Per rank: entries of F it stores.
    pub stored_entries: Vec<u64>,
    /// Jacobi: every sweep.
    pub sweeps: Vec<super::jacobi::Sweep>,
    /// Stochastic Jacobi: where its shooting iterations' time went (this rank's view).
    pub shooting: Option<crate::solve::stochastic_jacobi::Timing>,
}

impl Report {
    /// Bytes all ranks sent, in all.
    pub fn bytes_sent(&self) -> u64 {
        self.traffic.iter().map(|t| t.bytes_sent).sum()
    }

    /// Gather every rank's busy time and its traffic since `start` (this one's `busy`
    /// seconds).
    pub fn finish(&mut self, busy: f64, start: &Traffic, ranks: &Ranks<'_>) {
        let traffic = ranks.traffic().since(start);
        let per_rank = ranks.all_gather(&[
            busy,
            traffic.calls as f64,
            traffic.bytes_sent as f64,
            traffic.bytes_received as f64,
            traffic.seconds,
        ]);
        for r in per_rank.chunks_exact(5) {
            self.busy.push(r[0]);
            self.traffic.push(Traffic {
                calls: r[1] as u64,
                bytes_sent: r[2] as u64,
                bytes_received: r[3] as u64,
                seconds: r[4],
            });
        }
    }

    /// Load balance: the mean rank's busy time over the busiest's (1 when even).
    pub fn balance(&self) -> f64 {
        let max = self.busy.iter().copied().fold(0.0, f64::max);
        if max > 0.0 {
            self.busy.iter().sum::<f64>() / self.busy.len() as f64 / max
        } else {
            1.0
        }
    }
}

/// The message for a method that does not run over several ranks, and why.
pub fn not_distributed(what: &str, why: &str) -> Error {
    Error::NotDistributed(format!(
        "{what} does not run over several ranks ({why}); the distributed methods are solve --solver jacobi or stochastic-jacobi, form-factors and thermal"
    ))
}
