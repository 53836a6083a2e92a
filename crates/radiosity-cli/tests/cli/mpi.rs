//! Distributed runs (issue 21): with the `mpi` feature, the same bytes on 1, 2 and 4 ranks as
//! alone; without it, a binary launched as one of several ranks refuses. (`bench`'s refusal
//! over several ranks is with `bench`'s tests, in `bench.rs`.)

use crate::common::*;

/// Issue 21: every distributed method gives the same bytes on 1, 2 and 4 ranks, on the Cornell
/// box, the city and the hospital; the stochastic methods and the view factors also equal a run
/// without mpirun byte for byte.
#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs the mpi feature (cargo test --features mpi) and Open MPI's mpirun"
)]
#[cfg_attr(
    feature = "mpi",
    ignore = "needs RenderPark's and View3D's scenes in ../shared/scenes (run with --include-ignored, as .ci/run does)"
)]
fn mpi_ranks_give_identical_bytes() {
    #[cfg(feature = "mpi")]
    {
        let dir = scratch("mpi-bytes");
        let hospital = shared_renderpark("hospital/hosp.mgf");
        let hospital = hospital.to_str().unwrap();
        write(
            &dir,
            "bc.csv",
            "name,emissivity,temperature,flux\nzeq0,0.8,300,\nxeq0,0.5,400,\nyeq0,0.3,,\nzeq1,0.9,600,\nxeq1,0.7,,\nyeq1,0.6,800,\n",
        );
        let cube = shared_view3d("cube.vs3");
        let cube = cube.to_str().unwrap();
        let jobs: Vec<(&str, Vec<&str>)> = vec![
            (
                "cornell-jacobi.csv",
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "jacobi",
                    "--patches",
                    "1500",
                    "--tolerance",
                    "1e-4",
                ],
            ),
            (
                "cornell-sj.csv",
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "stochastic-jacobi",
                    "--patches",
                    "1500",
                ],
            ),
            (
                "city-jacobi.csv",
                vec![
                    "solve",
                    "city",
                    "--solver",
                    "jacobi",
                    "--max-edge",
                    "1e9",
                    "--rays",
                    "64",
                ],
            ),
            (
                "city-sj.csv",
                vec![
                    "solve",
                    "city",
                    "--solver",
                    "stochastic-jacobi",
                    "--max-edge",
                    "1e9",
                ],
            ),
            (
                "hospital-jacobi.csv",
                vec![
                    "solve",
                    hospital,
                    "--one-sided",
                    "--solver",
                    "jacobi",
                    "--patches",
                    "8000",
                    "--rays",
                    "64",
                ],
            ),
            (
                "hospital-sj.csv",
                vec![
                    "solve",
                    hospital,
                    "--one-sided",
                    "--solver",
                    "stochastic-jacobi",
                    "--patches",
                    "8000",
                ],
            ),
            (
                "cornell.mtx",
                vec![
                    "form-factors",
                    "cornell",
                    "--patches",
                    "400",
                    "--rays",
                    "4000",
                ],
            ),
            (
                "city.mtx",
                vec!["form-factors", "city", "--faces", "--rays", "200"],
            ),
            (
                "hospital.mtx",
                vec![
                    "form-factors",
                    hospital,
                    "--patches",
                    "3000",
                    "--rays",
                    "300",
                ],
            ),
            (
                "cube.csv",
                vec![
                    "thermal",
                    cube,
                    "--boundary",
                    "bc.csv",
                    "--patches",
                    "150",
                    "--rays",
                    "3000",
                ],
            ),
            (
                "cube-jacobi.csv",
                vec![
                    "thermal",
                    cube,
                    "--boundary",
                    "bc.csv",
                    "--patches",
                    "150",
                    "--rays",
                    "3000",
                    "--linear-solver",
                    "jacobi",
                ],
            ),
        ];
        for (out, args) in &jobs {
            let mut bytes = Vec::new();
            for k in [1, 2, 4] {
                let name = format!("{k}-{out}");
                let mut all = args.clone();
                all.extend(["-o", &name]);
                let o = mpirun(k, &all, &dir);
                assert!(o.status.success(), "{k} ranks, {all:?}: {}", stderr(&o));
                let text = stdout(&o);
                assert!(
                    text.contains(&format!("ranks       {k} (MPI")),
                    "no ranks line: {text}"
                );
                bytes.push(read_bytes(&dir, &name));
            }
            assert!(bytes[0] == bytes[1], "{out}: 1 and 2 ranks differ");
            assert!(bytes[0] == bytes[2], "{out}: 1 and 4 ranks differ");
            // Without mpirun: the same bytes, but for Jacobi (which runs whole sweeps over
            // ranks, and row by row alone); thermal's default alone is LU, so the plain run is
            // given the BiCGSTAB that mpirun defaults to.
            if !out.contains("jacobi.csv") {
                let mut all = args.clone();
                let name = format!("serial-{out}");
                all.extend(["-o", &name, "--threads", "1"]);
                if *out == "cube.csv" {
                    all.extend(["--linear-solver", "iterative"]);
                }
                run_ok(&all, &dir);
                assert!(
                    read_bytes(&dir, &name) == bytes[0],
                    "{out}: mpirun differs from a plain run"
                );
            }
        }
    }
}

/// A binary built without the feature, launched as one of several ranks, says so instead of
/// running the whole job on every rank.
#[test]
#[cfg_attr(feature = "mpi", ignore = "checks the build without the mpi feature")]
fn launched_by_mpirun_without_the_feature_is_refused() {
    // With the feature (where this is ignored), `--include-ignored` runs nothing here.
    #[cfg(not(feature = "mpi"))]
    {
        let dir = scratch("mpi-absent");
        let o = bin()
            .args(["solve", "cornell", "-o", "x.csv"])
            .env("OMPI_COMM_WORLD_SIZE", "4")
            .current_dir(&dir)
            .output()
            .unwrap();
        assert_fails(&o, &["4 MPI ranks", "--features mpi"], &dir, &[]);
        // A plain command inside a batch job (Slurm's variables, no MPI launcher's) runs.
        let o = bin()
            .args(["solve", "cornell", "--patches", "200", "-o", "x.csv"])
            .env("SLURM_NTASKS", "16")
            .current_dir(&dir)
            .output()
            .unwrap();
        succeed(&o);
    }
}

/// Issue 21: the sequential methods and the commands that do not distribute refuse clearly
/// over several ranks, naming the distributed alternatives, and write nothing.
#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs the mpi feature (cargo test --features mpi) and Open MPI's mpirun"
)]
fn mpi_refuses_what_does_not_distribute() {
    #[cfg(feature = "mpi")]
    {
        let dir = scratch("mpi-refuse");
        for (args, needles) in [
            (
                vec!["solve", "cornell", "--solver", "progressive", "-o", "x.csv"],
                vec!["--solver progressive", "stochastic-jacobi"],
            ),
            (
                vec!["solve", "cornell", "--solver", "southwell", "-o", "x.csv"],
                vec!["southwell", "jacobi"],
            ),
            (
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "hierarchical",
                    "-o",
                    "x.csv",
                ],
                vec!["hierarchical", "stochastic-jacobi"],
            ),
            (
                vec!["render", "cornell", "-o", "x.png"],
                vec!["render", "without mpirun"],
            ),
        ] {
            let o = mpirun(2, &args, &dir);
            let err = stderr(&o);
            assert!(!o.status.success(), "{args:?} succeeded");
            let lines: Vec<&str> = err
                .lines()
                .filter(|l| l.starts_with("radiosity: error"))
                .collect();
            assert_eq!(lines.len(), 1, "{args:?}: {err}");
            for n in needles {
                assert!(lines[0].contains(n), "'{}' lacks '{n}'", lines[0]);
            }
            assert!(!dir.join("x.csv").exists() && !dir.join("x.png").exists());
        }
    }
}
