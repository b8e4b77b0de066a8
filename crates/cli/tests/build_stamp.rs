//! The build script's triggers (`crates/cli/build.rs`): reading the repository (`git status`,
//! `git describe --dirty`, what a user and the script itself do) touches none of the paths the
//! script watches, so a second `cargo build` finds nothing to do.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::SystemTime;

/// The `rerun-if-changed` paths of this build's run of the script, absolute.
fn watched_paths() -> Vec<PathBuf> {
    // The script's output lies beside its OUT_DIR.
    let out_dir = Path::new(env!("OUT_DIR"));
    let output = std::fs::read_to_string(out_dir.with_file_name("output"))
        .expect("the build script's output beside OUT_DIR");
    let package = Path::new(env!("CARGO_MANIFEST_DIR"));
    output
        .lines()
        .filter_map(|line| {
            line.strip_prefix("cargo:rerun-if-changed=")
                .or_else(|| line.strip_prefix("cargo::rerun-if-changed="))
        })
        .map(|path| package.join(path))
        .collect()
}

/// The newest modification time of `path`, or of any file below it for a directory (as cargo
/// compares them).
fn newest(path: &Path) -> Option<SystemTime> {
    let meta = std::fs::metadata(path).ok()?;
    let own = meta.modified().ok();
    if !meta.is_dir() {
        return own;
    }
    std::fs::read_dir(path)
        .ok()?
        .filter_map(Result::ok)
        .filter_map(|entry| newest(&entry.path()))
        .chain(own)
        .max()
}

fn git(args: &[&str]) -> bool {
    Command::new("git")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn reading_the_repository_touches_no_path_the_build_script_watches() {
    let paths = watched_paths();
    if !git(&["rev-parse", "--git-dir"]) {
        hystcomp_testkit::skip("not built from a git checkout: the build script watches no refs");
        return;
    }
    assert!(
        paths.iter().any(|p| p.ends_with("HEAD")),
        "the script watches the checked-out commit: {paths:?}"
    );
    for path in &paths {
        let shown = path.display().to_string();
        assert!(
            !shown.ends_with("index") && !shown.contains("/logs/"),
            "{shown}: git rewrites it on reads (status, describe), so every build would rerun"
        );
        assert!(
            path.exists(),
            "{shown}: a missing path makes cargo rerun every build"
        );
    }
    let before: Vec<_> = paths.iter().map(|p| newest(p)).collect();
    // What users and the script do between two builds; the first one rewrites the index.
    assert!(git(&["status", "--short"]));
    assert!(git(&["describe", "--always", "--dirty", "--tags"]));
    assert!(git(&["status", "--short"]));
    let after: Vec<_> = paths.iter().map(|p| newest(p)).collect();
    for ((path, before), after) in paths.iter().zip(before).zip(after) {
        assert_eq!(
            before,
            after,
            "{} changed on a read of the repository",
            path.display()
        );
    }
}

#[test]
fn version_names_the_commit_the_binary_was_built_from() {
    let output = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
        .arg("--version")
        .output()
        .expect("hystcomp --version runs");
    let version = String::from_utf8_lossy(&output.stdout);
    assert!(
        version.starts_with(&format!("hystcomp {}", env!("CARGO_PKG_VERSION"))),
        "{version}"
    );
    let described = Command::new("git")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["describe", "--always", "--tags"])
        .output()
        .ok()
        .filter(|o| o.status.success());
    let Some(described) = described else {
        hystcomp_testkit::skip("not built from a git checkout: --version names no commit");
        return;
    };
    let commit = String::from_utf8_lossy(&described.stdout).trim().to_owned();
    assert!(
        version.contains(&format!("(git {commit}")),
        "{version} does not name {commit}"
    );
}
