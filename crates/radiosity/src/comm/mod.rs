//! The communicator of a distributed run: a leaf below the solvers, the pipelines and the
//! distributed drivers alike.
//!
//! The library knows no MPI: it sees a [`Communicator`] — rank, size and three collectives on
//! bytes (all-gather, gather to a root, all-to-all) — which the program implements over MPI
//! (the `mpi` feature of the CLI, rsmpi over Open MPI), [`Serial`] implements for one process
//! and [`Local`] for threads standing in for ranks (tests). [`Ranks`] wraps a communicator with
//! typed helpers and counts the traffic; [`balance`] splits work into contiguous blocks by
//! cost, the same on every rank.

mod local;

pub use local::Local;

use crate::color::Rgb;
use std::cell::Cell;
use std::ops::Range;
use std::time::Instant;

/// The collectives a distributed run needs, on raw bytes. Every rank calls the same
/// collectives in the same order.
pub trait Communicator {
    /// This process's rank, `0..size()`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Every rank's `mine`, concatenated in rank order into `out` on every rank; returns each
    /// rank's length in bytes.
    fn all_gather(&self, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize>;
    /// Every rank's `mine`, concatenated in rank order into `out` on `root` (left empty on the
    /// others); returns each rank's length on `root`, nothing elsewhere.
    fn gather(&self, root: usize, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize>;
    /// `send[k]` goes to rank k; returns what each rank sent to this one, by rank.
    fn all_to_all(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>>;
    /// Wait for every rank.
    fn barrier(&self);
    /// The transport, for reports ("serial", "MPI 3.1, Open MPI v4.1.4").
    fn describe(&self) -> String;
}

/// One process: every collective is a copy.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Communicator for Serial {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_gather(&self, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
        out.clear();
        out.extend_from_slice(mine);
        vec![mine.len()]
    }
    fn gather(&self, _root: usize, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
        self.all_gather(mine, out)
    }
    fn all_to_all(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>> {
        send.to_vec()
    }
    fn barrier(&self) {}
    fn describe(&self) -> String {
        "serial (one process)".into()
    }
}

/// What this rank has sent and waited for in collectives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Traffic {
    /// Collective calls.
    pub calls: u64,
    /// Bytes this rank contributed to them.
    pub bytes_sent: u64,
    /// Bytes it received from them.
    pub bytes_received: u64,
    /// Seconds spent inside them (waiting for the slowest rank included).
    pub seconds: f64,
}

impl Traffic {
    /// What was done after `earlier` (a snapshot of the same count).
    pub fn since(&self, earlier: &Traffic) -> Traffic {
        Traffic {
            calls: self.calls - earlier.calls,
            bytes_sent: self.bytes_sent - earlier.bytes_sent,
            bytes_received: self.bytes_received - earlier.bytes_received,
            seconds: self.seconds - earlier.seconds,
        }
    }
}

/// A communicator with typed collectives and a traffic count.
pub struct Ranks<'c> {
    comm: &'c dyn Communicator,
    traffic: Cell<Traffic>,
}

impl std::fmt::Debug for Ranks<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ranks")
            .field("rank", &self.rank())
            .field("size", &self.size())
            .field("traffic", &self.traffic.get())
            .finish()
    }
}

impl<'c> Ranks<'c> {
    /// Wrap `comm`.
    pub fn new(comm: &'c dyn Communicator) -> Self {
        Self {
            comm,
            traffic: Cell::new(Traffic::default()),
        }
    }

    /// This rank.
    pub fn rank(&self) -> usize {
        self.comm.rank()
    }

    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.comm.size()
    }

    /// True on rank 0, the one that reports and writes files.
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// The communicator.
    pub fn communicator(&self) -> &'c dyn Communicator {
        self.comm
    }

    /// Traffic so far.
    pub fn traffic(&self) -> Traffic {
        self.traffic.get()
    }

    fn count(&self, sent: usize, received: usize, t: Instant) {
        let mut x = self.traffic.get();
        x.calls += 1;
        x.bytes_sent += sent as u64;
        x.bytes_received += received as u64;
        x.seconds += t.elapsed().as_secs_f64();
        self.traffic.set(x);
    }

    /// Every rank's `mine`, concatenated in rank order, on every rank.
    pub fn all_gather<T: Plain>(&self, mine: &[T]) -> Vec<T> {
        let bytes = encode(mine);
        let t = Instant::now();
        let mut out = Vec::new();
        self.comm.all_gather(&bytes, &mut out);
        self.count(bytes.len(), out.len(), t);
        decode(&out)
    }

    /// Every rank's `mine`, concatenated in rank order, on `root`; empty elsewhere.
    pub fn gather<T: Plain>(&self, root: usize, mine: &[T]) -> Vec<T> {
        let bytes = encode(mine);
        let t = Instant::now();
        let mut out = Vec::new();
        self.comm.gather(root, &bytes, &mut out);
        self.count(bytes.len(), out.len(), t);
        decode(&out)
    }

    /// `send[k]` to rank k; what each rank sent here, by rank.
    pub fn all_to_all<T: Plain>(&self, send: &[Vec<T>]) -> Vec<Vec<T>> {
        let bytes: Vec<Vec<u8>> = send.iter().map(|v| encode(v)).collect();
        let t = Instant::now();
        let got = self.comm.all_to_all(&bytes);
        let sent: usize = bytes.iter().map(Vec::len).sum();
        let received: usize = got.iter().map(Vec::len).sum();
        self.count(sent, received, t);
        got.iter().map(|b| decode(b)).collect()
    }

    /// The same value on every rank: rank 0's.
    pub fn agree<T: Plain>(&self, value: T) -> T {
        self.all_gather(&[value])[0]
    }

    /// Wait for every rank.
    pub fn barrier(&self) {
        let t = Instant::now();
        self.comm.barrier();
        self.count(0, 0, t);
    }
}

/// Values sent as little-endian bytes.
pub trait Plain: Copy {
    /// Bytes a value takes.
    const SIZE: usize;
    /// Append the value's bytes.
    fn put(&self, out: &mut Vec<u8>);
    /// Read a value from exactly [`Self::SIZE`] bytes.
    fn get(bytes: &[u8]) -> Self;
}

macro_rules! plain_number {
    ($($t:ty),*) => {$(
        impl Plain for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn get(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(bytes.try_into().expect("exact size"))
            }
        }
    )*};
}
plain_number!(u8, u32, u64, f32, f64);

impl Plain for Rgb {
    const SIZE: usize = 24;
    fn put(&self, out: &mut Vec<u8>) {
        for c in [self.r, self.g, self.b] {
            c.put(out);
        }
    }
    fn get(bytes: &[u8]) -> Self {
        Rgb::new(
            f64::get(&bytes[0..8]),
            f64::get(&bytes[8..16]),
            f64::get(&bytes[16..24]),
        )
    }
}

impl<A: Plain, B: Plain> Plain for (A, B) {
    const SIZE: usize = A::SIZE + B::SIZE;
    fn put(&self, out: &mut Vec<u8>) {
        self.0.put(out);
        self.1.put(out);
    }
    fn get(bytes: &[u8]) -> Self {
        (A::get(&bytes[..A::SIZE]), B::get(&bytes[A::SIZE..]))
    }
}

/// `values` as bytes.
pub fn encode<T: Plain>(values: &[T]) -> Vec<u8> {
    let mut out = Vec::with_capacity(values.len() * T::SIZE);
    for v in values {
        v.put(&mut out);
    }
    out
}

/// Bytes back to values (a trailing partial value is ignored; the collectives never make one).
pub fn decode<T: Plain>(bytes: &[u8]) -> Vec<T> {
    bytes.chunks_exact(T::SIZE).map(T::get).collect()
}

/// Split `0..costs.len()` into `parts` contiguous blocks of about equal total cost: block r
/// ends where the running cost first reaches (r + 1)/parts of the total. Deterministic in the
/// costs, so every rank that holds the same costs computes the same blocks.
pub fn balance(costs: &[f64], parts: usize) -> Vec<Range<usize>> {
    let parts = parts.max(1);
    let n = costs.len();
    let total: f64 = costs.iter().map(|c| c.max(0.0)).sum();
    let mut out = Vec::with_capacity(parts);
    if total <= 0.0 {
        for r in 0..parts {
            out.push(n * r / parts..n * (r + 1) / parts);
        }
        return out;
    }
    let (mut start, mut acc, mut i) = (0, 0.0, 0);
    for r in 0..parts {
        if r + 1 == parts {
            out.push(start..n);
            break;
        }
        let target = total * (r + 1) as f64 / parts as f64;
        while i < n && acc + costs[i].max(0.0) * 0.5 < target {
            acc += costs[i].max(0.0);
            i += 1;
        }
        out.push(start..i);
        start = i;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balance_splits_by_cost_not_count() {
        // Ten cheap rows and two expensive ones: the expensive ones get a rank to themselves.
        let mut costs = vec![1.0; 10];
        costs.extend([10.0, 10.0]);
        let b = balance(&costs, 3);
        assert_eq!(b, vec![0..10, 10..11, 11..12]);
        // Blocks cover everything exactly once, also with more ranks than rows.
        for parts in 1..20 {
            let b = balance(&costs, parts);
            assert_eq!(b.len(), parts);
            assert_eq!(b[0].start, 0);
            assert_eq!(b.last().unwrap().end, costs.len());
            for w in b.windows(2) {
                assert_eq!(w[0].end, w[1].start);
            }
        }
        assert_eq!(balance(&[0.0; 4], 2), vec![0..2, 2..4]);
    }

    #[test]
    fn plain_values_round_trip() {
        let v = vec![(3u32, 0.25f32), (u32::MAX, -1.5)];
        assert_eq!(decode::<(u32, f32)>(&encode(&v)), v);
        let c = vec![Rgb::new(1.0, -2.0, 1e-300)];
        assert_eq!(decode::<Rgb>(&encode(&c)), c);
        let ranks = Ranks::new(&Serial);
        assert_eq!(ranks.all_gather(&[1.5f64, 2.5]), vec![1.5, 2.5]);
        assert_eq!(ranks.traffic().calls, 1);
        assert_eq!(ranks.traffic().bytes_sent, 16);
    }
}
