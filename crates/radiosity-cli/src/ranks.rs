//! Runs under `mpirun`: the ranks of this process, when the `mpi` feature is built and the
//! program was launched by an MPI launcher; otherwise none, and every command runs as on one
//! machine.
//!
//! The communicator lives for the whole process (leaked: MPI is initialized once and finalized
//! by [`finish`] at exit), and is reached through [`current`] from the commands that distribute
//! their work (`solve` with Jacobi or stochastic Jacobi, `form-factors`, `thermal`, `bench
//! --ranks`). Only rank 0 prints and writes files; the others' standard output is discarded.

use radiosity::distributed::Ranks;
use std::cell::Cell;

thread_local! {
    static CURRENT: Cell<Option<&'static Ranks<'static>>> = const { Cell::new(None) };
}

/// The ranks of this run, when it was launched by `mpirun` and built with the `mpi` feature.
pub fn current() -> Option<&'static Ranks<'static>> {
    CURRENT.with(Cell::get)
}

/// True unless this is a rank other than 0 of a distributed run.
pub fn is_root() -> bool {
    current().is_none_or(Ranks::is_root)
}

/// More than one rank.
pub fn distributed() -> bool {
    current().is_some_and(|r| r.size() > 1)
}

/// Whether an MPI launcher started this process, and as one of how many ranks when it says:
/// Open MPI's `mpirun` (`OMPI_COMM_WORLD_SIZE`), MPICH's and Intel MPI's Hydra and Slurm's
/// `srun --mpi=pmi2` (`PMI_SIZE`), PMIx launchers such as `srun --mpi=pmix` (`PMIX_RANK`, the size
/// then from `SLURM_NTASKS` when set). A plain command inside a batch job is not launched.
pub fn launched() -> Option<Option<usize>> {
    let number = |v: &str| std::env::var(v).ok()?.trim().parse::<usize>().ok();
    if let Some(k) = number("OMPI_COMM_WORLD_SIZE").or_else(|| number("PMI_SIZE")) {
        return Some(Some(k));
    }
    std::env::var_os("PMIX_RANK").map(|_| number("SLURM_NTASKS"))
}

/// Set up the ranks: MPI when launched by a launcher and built with the feature. An error when
/// launched on several ranks without the feature (every process would run the whole job and
/// write the same files).
pub fn start() -> anyhow::Result<()> {
    let Some(size) = launched() else {
        return Ok(());
    };
    #[cfg(feature = "mpi")]
    {
        let _ = size;
        let ranks: &'static Ranks<'static> = Box::leak(Box::new(Ranks::new(mpi::world()?)));
        if !ranks.is_root() {
            mpi::silence_stdout();
        }
        CURRENT.with(|c| c.set(Some(ranks)));
        Ok(())
    }
    #[cfg(not(feature = "mpi"))]
    {
        let rank = ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"]
            .iter()
            .find_map(|v| std::env::var(v).ok()?.trim().parse::<usize>().ok());
        if size.is_some_and(|k| k > 1) || rank.is_some_and(|r| r > 0) {
            let size = size.map_or("several".to_string(), |k| k.to_string());
            anyhow::bail!(
                "launched as one of {size} MPI ranks, but this radiosity was built without the mpi feature: every rank would run the whole job; build it with `cargo build --release -p radiosity-cli --features mpi` (see the README)"
            );
        }
        Ok(())
    }
}

/// An error in a distributed run: rank 0 prints it; a rank that failed alone prints it with
/// its rank after a moment (when all failed alike, rank 0's abort has ended it by then); then
/// every rank stops the whole run, so that none waits forever in a collective.
pub fn fail(message: &str) -> ! {
    let r = current().expect("called only in a distributed run");
    // One write for the whole line, so that the launcher's own messages cannot split it; then
    // a moment for the launcher to forward it before the abort's banner.
    let line = if r.is_root() {
        format!("radiosity: error: {message}\n")
    } else {
        std::thread::sleep(std::time::Duration::from_secs(2));
        format!("radiosity: error: rank {}: {message}\n", r.rank())
    };
    {
        use std::io::Write as _;
        let mut err = std::io::stderr().lock();
        let _ = err.write_all(line.as_bytes());
        let _ = err.flush();
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    #[cfg(feature = "mpi")]
    mpi::abort(1);
    #[cfg(not(feature = "mpi"))]
    std::process::exit(1)
}

/// End MPI (every rank, after a successful command).
pub fn finish() {
    #[cfg(feature = "mpi")]
    if current().is_some() {
        mpi::finalize();
    }
}

/// Refuse a command that does not distribute its work when there are several ranks.
pub fn refuse_unless_single(what: &str) -> anyhow::Result<()> {
    if distributed() {
        anyhow::bail!(
            "{what} does not run over several ranks; the distributed commands are solve --solver jacobi or stochastic-jacobi, form-factors, thermal and radiosity-bench ranks (run {what} without mpirun)"
        );
    }
    Ok(())
}

#[cfg(feature = "mpi")]
mod mpi {
    //! The MPI transport: rsmpi over the system's MPI library (Open MPI on Debian). Two calls
    //! go below rsmpi (`MPI_Finalize` at a time of our choosing, and `dup2` to silence the other
    //! ranks' output): FFI is unsafe by nature, and they are confined to this module.
    #![allow(unsafe_code)]
    use mpi::datatype::PartitionMut;
    use mpi::topology::SimpleCommunicator;
    use mpi::traits::*;
    use radiosity::distributed::Communicator as Transport;

    /// `MPI_COMM_WORLD` of this process.
    pub struct World {
        comm: SimpleCommunicator,
        version: String,
    }

    /// Initialize MPI (funneled: only the main thread calls it; rayon's workers never do).
    pub fn world() -> anyhow::Result<&'static World> {
        let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)
            .ok_or_else(|| anyhow::anyhow!("MPI could not be initialized (was it already?)"))?;
        let comm = universe.world();
        let (major, minor) = mpi::environment::version();
        let version = format!(
            "MPI {major}.{minor}, {}",
            mpi::environment::library_version()
                .unwrap_or_default()
                .lines()
                .next()
                .unwrap_or("")
                .split(',')
                .next()
                .unwrap_or("")
                .trim()
        );
        // Finalized by `finalize`, not by dropping the universe.
        std::mem::forget(universe);
        let world: &'static World = Box::leak(Box::new(World { comm, version }));
        WORLD.with(|w| w.set(Some(world)));
        Ok(world)
    }

    thread_local! {
        static WORLD: std::cell::Cell<Option<&'static World>> = const { std::cell::Cell::new(None) };
    }

    /// `MPI_Finalize`.
    pub fn finalize() {
        // SAFETY: MPI was initialized by `world` on this (the main) thread, every rank has left
        // its collectives, and nothing calls MPI afterwards.
        unsafe {
            mpi::ffi::MPI_Finalize();
        }
    }

    /// `MPI_Abort` on the world: ends every rank.
    pub fn abort(code: i32) -> ! {
        match WORLD.with(std::cell::Cell::get) {
            Some(w) => w.comm.abort(code),
            None => std::process::exit(code),
        }
    }

    extern "C" {
        fn dup2(old: std::ffi::c_int, new: std::ffi::c_int) -> std::ffi::c_int;
    }

    /// Discard this process's standard output (ranks other than 0 report nothing).
    pub fn silence_stdout() {
        use std::os::fd::AsRawFd;
        if let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") {
            // SAFETY: both descriptors are open; dup2 replaces descriptor 1 atomically.
            unsafe {
                dup2(null.as_raw_fd(), 1);
            }
        }
    }

    fn counts(n: usize, sizes: &[i32]) -> (Vec<i32>, Vec<i32>) {
        let mut displs = Vec::with_capacity(n);
        let mut at = 0i32;
        for &c in sizes {
            displs.push(at);
            at += c;
        }
        (sizes.to_vec(), displs)
    }

    fn length(len: usize) -> i32 {
        i32::try_from(len).expect("a message under 2 GiB (the rows and rays are sent in batches)")
    }

    impl Transport for World {
        fn rank(&self) -> usize {
            self.comm.rank() as usize
        }
        fn size(&self) -> usize {
            self.comm.size() as usize
        }
        fn all_gather(&self, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
            let n = self.size();
            let mut sizes = vec![0i32; n];
            self.comm
                .all_gather_into(&length(mine.len()), &mut sizes[..]);
            let (c, d) = counts(n, &sizes);
            out.clear();
            out.resize(sizes.iter().map(|&s| s as usize).sum(), 0);
            let mut p = PartitionMut::new(&mut out[..], c, &d[..]);
            self.comm.all_gather_varcount_into(mine, &mut p);
            sizes.iter().map(|&s| s as usize).collect()
        }
        fn gather(&self, root: usize, mine: &[u8], out: &mut Vec<u8>) -> Vec<usize> {
            let n = self.size();
            let proc = self.comm.process_at_rank(root as i32);
            out.clear();
            if self.rank() == root {
                let mut sizes = vec![0i32; n];
                proc.gather_into_root(&length(mine.len()), &mut sizes[..]);
                let (c, d) = counts(n, &sizes);
                out.resize(sizes.iter().map(|&s| s as usize).sum(), 0);
                let mut p = PartitionMut::new(&mut out[..], c, &d[..]);
                proc.gather_varcount_into_root(mine, &mut p);
                sizes.iter().map(|&s| s as usize).collect()
            } else {
                proc.gather_into(&length(mine.len()));
                proc.gather_varcount_into(mine);
                Vec::new()
            }
        }
        fn all_to_all(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>> {
            let n = self.size();
            let send_sizes: Vec<i32> = send.iter().map(|s| length(s.len())).collect();
            let mut recv_sizes = vec![0i32; n];
            self.comm
                .all_to_all_into(&send_sizes[..], &mut recv_sizes[..]);
            let flat: Vec<u8> = send.concat();
            let (sc, sd) = counts(n, &send_sizes);
            let (rc, rd) = counts(n, &recv_sizes);
            let mut out = vec![0u8; recv_sizes.iter().map(|&s| s as usize).sum()];
            {
                let sp = mpi::datatype::Partition::new(&flat[..], sc, &sd[..]);
                let mut rp = PartitionMut::new(&mut out[..], rc, &rd[..]);
                self.comm.all_to_all_varcount_into(&sp, &mut rp);
            }
            (0..n)
                .map(|k| out[rd[k] as usize..(rd[k] + recv_sizes[k]) as usize].to_vec())
                .collect()
        }
        fn barrier(&self) {
            self.comm.barrier();
        }
        fn describe(&self) -> String {
            self.version.clone()
        }
    }
}
