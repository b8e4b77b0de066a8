//! Records `git describe` of the sources at build time, for the report's software version.

use std::process::Command;

/// What `git` prints for `args` in this crate's directory, trimmed; `None` when git fails.
fn git(args: &[&str]) -> Option<String> {
    Command::new("git")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty())
}

fn main() {
    if let Some(describe) = git(&["describe", "--always", "--dirty", "--tags"]) {
        println!("cargo:rustc-env=HYSTCOMP_GIT_DESCRIBE={describe}");
    }
    // Describe again when the checked-out commit, the branch it is on or the staged state
    // changes (`--git-path` also finds them in a worktree), and when any source of the
    // workspace's crates changes (for `-dirty`).
    // (A path that does not exist would make cargo run this script on every build.)
    let branch = git(&["symbolic-ref", "-q", "HEAD"]);
    let names = ["HEAD", "index", "packed-refs"]
        .into_iter()
        .chain(branch.as_deref());
    for name in names {
        if let Some(path) = git(&["rev-parse", "--git-path", name])
            && std::path::Path::new(&path).exists()
        {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    println!("cargo:rerun-if-changed=../../crates");
}
