//! The workspace's structure (issue 31): no import cycle between the files of a crate, as
//! `scripts/file-cycles.py` draws them. The script is also run on a small tree with a cycle, so
//! this test is seen to fail when one is there.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn file_cycles(root: Option<&Path>) -> Output {
    let mut cmd = Command::new("python3");
    cmd.arg(repo().join("scripts/file-cycles.py"));
    if let Some(r) = root {
        cmd.arg("--root").arg(r);
    }
    cmd.output()
        .expect("python3 runs scripts/file-cycles.py (CI installs python3)")
}

#[test]
fn no_file_imports_another_that_imports_it_back() {
    let o = file_cycles(None);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "file cycles found:\n{err}");
    assert!(err.contains("no file cycles"), "{err}");
}

#[test]
fn a_cycle_between_two_files_is_found() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("crates/demo/src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\nmod c;\n").unwrap();
    // a -> b -> a is a cycle; c -> a alone is not.
    std::fs::write(src.join("a.rs"), "use crate::b::B;\npub struct A;\n").unwrap();
    std::fs::write(
        src.join("b.rs"),
        "pub struct B;\nfn f() -> crate::a::A { crate::a::A }\n",
    )
    .unwrap();
    std::fs::write(src.join("c.rs"), "use crate::a::A;\n").unwrap();
    let o = file_cycles(Some(dir.path()));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cycle in demo: crates/demo/src/a.rs, crates/demo/src/b.rs\n"),
        "{err}"
    );
    assert!(err.contains("1 file cycle(s)"), "{err}");
}
