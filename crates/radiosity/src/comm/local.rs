//! Ranks as threads of one process ([`Local`]): the collectives through shared memory and a
//! barrier. For tests of the distributed methods without MPI, and for checking that a method
//! gives the same bytes on any number of ranks.

use super::Communicator;
use std::sync::{Arc, Barrier, Mutex};

struct Shared {
    size: usize,
    barrier: Barrier,
    /// `slots[from * size + to]`: what rank `from` sends to rank `to` in the current collective.
    slots: Mutex<Vec<Vec<u8>>>,
}

/// One rank of a group of threads made by [`Local::group`].
pub struct Local {
    rank: usize,
    shared: Arc<Shared>,
}

impl Local {
    /// A communicator for each of `size` ranks; hand one to each thread.
    pub fn group(size: usize) -> Vec<Local> {
        let shared = Arc::new(Shared {
            size,
            barrier: Barrier::new(size),
            slots: Mutex::new(vec![Vec::new(); size * size]),
        });
        (0..size)
            .map(|rank| Local {
                rank,
                shared: shared.clone(),
            })
            .collect()
    }

    /// Run `f(rank's communicator)` on `size` threads at once; the results by rank.
    pub fn run<T: Send>(size: usize, f: impl Fn(&Local) -> T + Sync) -> Vec<T> {
        let group = Local::group(size);
        std::thread::scope(|s| {
            let handles: Vec<_> = group.iter().map(|c| s.spawn(|| f(c))).collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("rank thread panicked"))
                .collect()
        })
    }

    fn exchange(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>> {
        let n = self.shared.size;
        {
            let mut slots = self.shared.slots.lock().expect("not poisoned");
            for (to, bytes) in send.iter().enumerate() {
                slots[self.rank * n + to] = bytes.clone();
            }
        }
        self.shared.barrier.wait();
        let got = {
            let slots = self.shared.slots.lock().expect("not poisoned");
            (0..n)
                .map(|from| slots[from * n + self.rank].clone())
                .collect()
        };
        // Nobody writes the next collective's slots before everyone has read these.
        self.shared.barrier.wait();
        got
    }
}

impl Communicator for Local {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.size
    }
    fn all_gather(&self, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
        let got = self.exchange(&vec![mine.to_vec(); self.shared.size]);
        out.clear();
        for g in &got {
            out.extend_from_slice(g);
        }
        got.iter().map(Vec::len).collect()
    }
    fn gather(&self, root: usize, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
        let mut send = vec![Vec::new(); self.shared.size];
        send[root] = mine.to_vec();
        let got = self.exchange(&send);
        out.clear();
        if self.rank != root {
            return Vec::new();
        }
        for g in &got {
            out.extend_from_slice(g);
        }
        got.iter().map(Vec::len).collect()
    }
    fn all_to_all(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>> {
        self.exchange(send)
    }
    fn barrier(&self) {
        self.shared.barrier.wait();
    }
    fn describe(&self) -> String {
        format!("{} ranks as threads of one process", self.shared.size)
    }
}
