//! Work split over the ranks of a distributed run (MPI), with results identical to one rank.
//!
//! The library knows no MPI: it sees a [`Communicator`] ([`crate::comm`], a leaf below the
//! solvers), which the program implements over MPI. This module holds only what is
//! distributed: the row blocks ([`rows`]), the Jacobi sweeps over them ([`jacobi`]) and the
//! run's [`Report`]; the pipelines that use them take the ranks as an argument
//! ([`crate::pipeline::solve_over`], [`crate::pipeline::thermal_over`],
//! [`crate::pipeline::view_factors_over`]).
//!
//! **Data distribution.** Every rank holds the scene, the mesh and its BVH (a few hundred bytes a
//! patch: 10⁷ patches fit a node of 16 GiB). What is split is the O(N·rays) work and the O(nnz)
//! matrix: rank r owns a contiguous block of patches, balanced by the estimated cost of their
//! rows ([`balance`], [`rows::row_costs`]), computes their rows of F and keeps them
//! ([`rows::RowBlock`]). The O(N) vectors (B, the unshot radiosity) are replicated: after each
//! iteration every rank's block is all-gathered.
//!
//! **Identical results for any number of ranks.** Each row of F and each ray chunk has its own
//! random stream keyed by its index, never by its rank; every rank receives every block in rank
//! order, so the full vectors are the same bytes everywhere; every reduction (norms, energy
//! sums) runs over those full vectors in patch order on every rank. Nothing is summed across
//! ranks in floating point, where the association would depend on the rank count.
//!
//! Methods: [`jacobi`] (sweeps over the owned rows), stochastic Jacobi
//! ([`crate::solve::stochastic_jacobi`], each rank tracing its share of every iteration's ray
//! chunks), view-factor rows ([`rows`]) and the thermal Jacobi ([`crate::thermal`]). The sequential
//! methods (progressive refinement, Southwell, overshooting, Gauss-Seidel, photon shooting)
//! relax one row after another and are not distributed.

pub mod jacobi;
mod report;
pub mod rows;

pub use crate::comm::{
    balance, decode, encode, Communicator, Local, Plain, Ranks, Serial, Traffic,
};
pub use report::{not_distributed, Report, DISTRIBUTED_SOLVERS};
