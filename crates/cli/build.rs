//! Records `git describe` of the sources at build time, for the report's software version and
//! `hystcomp --version` (`HYSTCOMP_GIT_DESCRIBE`, `HYSTCOMP_VERSION`).
//!
//! # When it runs again (and why a second `cargo build` does nothing)
//! Cargo runs this script again, and so rebuilds the binary, only when one of the paths it
//! names with `rerun-if-changed` is newer than its last run:
//! - the checked-out commit: `HEAD`, the branch `HEAD` points to, `packed-refs` and the tags
//!   directory (found with `git rev-parse --git-path`, so also in a worktree); these change on
//!   commit, checkout, reset and tag, never on a read;
//! - the workspace's sources (`crates/`, `Cargo.toml`, `Cargo.lock`), whose edits make the
//!   tree `-dirty`.
//!
//! It no longer watches `.git/index`: `git describe --dirty` and `git status` refresh and
//! rewrite the index, so a script that watched it rebuilt the binary on every `cargo run` of a
//! tree with a change in it. Git runs here with `GIT_OPTIONAL_LOCKS=0`, so describing writes
//! nothing into `.git`. `crates/cli/tests/build_stamp.rs` checks both properties (no watched
//! path under `.git` but refs, and none that `git status` or `git describe` touches). Measured
//! on a dirty tree: the second `cargo build -p hystcomp` prints only `Finished` (0.4 s, nothing
//! compiled), where it used to recompile and relink the binary each time.

use std::path::Path;
use std::process::Command;

/// What `git` prints for `args` in this crate's directory, trimmed; `None` when git fails.
/// Git takes no optional locks, so it never rewrites the index it reads.
fn git(args: &[&str]) -> Option<String> {
    Command::new("git")
        .env("GIT_OPTIONAL_LOCKS", "0")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty())
}

fn main() {
    let version = std::env::var("CARGO_PKG_VERSION").unwrap_or_default();
    match git(&["describe", "--always", "--dirty", "--tags"]) {
        Some(describe) => {
            println!("cargo:rustc-env=HYSTCOMP_GIT_DESCRIBE={describe}");
            println!("cargo:rustc-env=HYSTCOMP_VERSION={version} (git {describe})");
        }
        None => println!("cargo:rustc-env=HYSTCOMP_VERSION={version}"),
    }
    let branch = git(&["symbolic-ref", "-q", "HEAD"]);
    let names = ["HEAD", "packed-refs", "refs/tags"]
        .into_iter()
        .chain(branch.as_deref());
    for name in names {
        // (A path that does not exist would make cargo run this script on every build.)
        if let Some(path) = git(&["rev-parse", "--git-path", name])
            && Path::new(&path).exists()
        {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    for source in ["../../crates", "../../Cargo.toml", "../../Cargo.lock"] {
        println!("cargo:rerun-if-changed={source}");
    }
}
