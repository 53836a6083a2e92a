//! `radiosity fuzz` (with the hostile-input checks that share its test): a short seeded fuzz of
//! the option parser runs clean. Uses only `common`.

use crate::common::*;

/// More hostile-input classes: a face whose repeated vertex makes a zero-area patch is named
/// by its file and line; a missing file gives the operating system's message once; the
/// summary reports resident memory first; and a short seeded fuzz of the option parser runs
/// clean.
#[test]
fn located_errors_os_messages_once_resident_memory_and_option_fuzz() {
    let dir = scratch("hostile2");
    write(&dir, "l.mtl", "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    write(
        &dir,
        "deg.obj",
        "mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl light\nf 1 2 4 3\nf 1 2 2 3\n",
    );
    fails(
        &["solve", "deg.obj", "--patches", "100", "-o", "x.csv"],
        &dir,
        &["deg.obj:8", "area 0"],
        &["l.mtl", "deg.obj"],
    );
    let out = run(&["solve", "missing.obj", "-o", "x.csv"], &dir);
    let err = stderr(&out);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(err.contains("cannot read missing.obj"), "{err}");
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "x.csv"],
        &dir,
    );
    let text = stdout(&out);
    assert!(text.contains("memory      peak resident"), "{text}");
    let text = run_ok(
        &[
            "fuzz",
            "--cases",
            "500",
            "--targets",
            "options",
            "--out",
            "fz",
        ],
        &dir,
    );
    assert!(text.contains("options"));
}
