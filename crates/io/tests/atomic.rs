//! Tests of atomic writes: a reader or a crash sees the old file or the new one, never a
//! part, and a failure leaves nothing behind.

mod common;

use common::*;

use std::fs;

use hystcomp_io::atomic::{write_atomic, write_atomic_pair, write_atomic_with};
use hystcomp_io::data::{DataError, write_csv};

#[test]
fn atomic_write_replaces_the_whole_file_and_leaves_nothing_else() {
    let dir = dir();
    let path = dir.path().join("model.json");
    write_atomic(&path, b"a long first version of the file").expect("first write");
    write_atomic(&path, b"short").expect("second write");
    assert_eq!(fs::read(&path).expect("reading"), b"short");
    assert_eq!(entries(dir.path()), ["model.json"]);
}

#[test]
fn atomic_write_failing_midway_keeps_the_old_file_and_no_temporary() {
    let dir = dir();
    let path = dir.path().join("model.json");
    fs::write(&path, "the old model").expect("the old file");
    let error = write_atomic_with(&path, |out| {
        out.write_all(&[b'x'; 100_000])?;
        Err(std::io::Error::other("the encoder gave up"))
    })
    .expect_err("the writer fails");
    assert_contains(&error.to_string(), &["model.json", "the encoder gave up"]);
    assert_eq!(fs::read_to_string(&path).expect("kept"), "the old model");
    assert_eq!(entries(dir.path()), ["model.json"]);

    write_atomic_with(&path, |out| out.write_all(b"the new model")).expect("writing");
    assert_eq!(
        fs::read_to_string(&path).expect("replaced"),
        "the new model"
    );
    assert_eq!(entries(dir.path()), ["model.json"]);
}

#[test]
fn atomic_write_onto_a_directory_fails_and_leaves_it_intact() {
    let dir = dir();
    let target = dir.path().join("results");
    fs::create_dir(&target).expect("a directory");
    fs::write(target.join("inside.txt"), "keep").expect("a file inside");
    let error = write_atomic(&target, b"new").expect_err("a directory is not a file");
    assert_eq!(error.kind(), std::io::ErrorKind::IsADirectory);
    assert!(error.to_string().contains("results"), "{error}");
    assert_eq!(
        fs::read_to_string(target.join("inside.txt")).expect("kept"),
        "keep"
    );
    assert_eq!(entries(dir.path()), ["results"]);
    assert_eq!(entries(&target), ["inside.txt"]);

    let error = write_csv(&target, &["u"], &[&[1.0]]).expect_err("through write_csv");
    assert!(matches!(error, DataError::Write { .. }) && error.is_output());
    assert_contains(&error.to_string(), &["results"]);
    assert_eq!(entries(dir.path()), ["results"]);
}

#[test]
fn atomic_write_into_a_missing_directory_names_the_path() {
    let dir = dir();
    let path = dir.path().join("missing").join("out.csv");
    let error = write_atomic(&path, b"x").expect_err("no directory");
    assert_eq!(error.kind(), std::io::ErrorKind::NotFound);
    assert!(error.to_string().contains("out.csv"), "{error}");
    assert_eq!(entries(dir.path()), Vec::<String>::new());
}

/// The environment variable that tells [`write_into_locked_directory_as_child`] which file to
/// write (set only by the test below for the child it starts).
#[cfg(unix)]
const CHILD_TARGET: &str = "HYSTCOMP_ATOMIC_CHILD_TARGET";

/// A write into a read-only directory fails, naming the file, and leaves the old file and
/// nothing else. As root (CI runs as root), whom permissions do not stop, the write runs in a
/// child process of this test binary with the privileges dropped to `nobody` by `setpriv`
/// (util-linux), so that the failure path really runs.
#[cfg(unix)]
#[test]
fn atomic_write_in_a_read_only_directory_keeps_the_old_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = dir();
    // Others may enter the folder (the unprivileged child must reach the locked one).
    fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o755)).expect("chmod");
    let locked = dir.path().join("locked");
    fs::create_dir(&locked).expect("a directory");
    let path = locked.join("model.json");
    fs::write(&path, "old").expect("the old file");
    fs::set_permissions(&path, fs::Permissions::from_mode(0o644)).expect("chmod");
    fs::set_permissions(&locked, fs::Permissions::from_mode(0o555)).expect("read-only");

    let message = if is_root() {
        let setpriv = hystcomp_testkit::find_on_path("setpriv");
        if !hystcomp_testkit::require_tool(
            "setpriv",
            setpriv.is_some(),
            "apt-get install util-linux",
        ) {
            fs::set_permissions(&locked, fs::Permissions::from_mode(0o755)).expect("restore");
            return;
        }
        let exe = std::env::current_exe().expect("this test binary");
        let output = std::process::Command::new(setpriv.expect("found above"))
            .args(["--reuid=65534", "--regid=65534", "--clear-groups", "--"])
            .arg(&exe)
            .args([
                "--ignored",
                "--exact",
                "write_into_locked_directory_as_child",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(CHILD_TARGET, &path)
            .output()
            .expect("setpriv runs");
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        assert!(
            output.status.success() && stdout.contains("1 passed"),
            "the unprivileged child failed: {}\n{stdout}\n{stderr}",
            output.status
        );
        stderr
    } else {
        write_atomic(&path, b"new")
            .expect_err("a read-only directory")
            .to_string()
    };
    fs::set_permissions(&locked, fs::Permissions::from_mode(0o755)).expect("restore");
    assert!(message.contains("model.json"), "{message}");
    assert!(message.contains("no permission"), "{message}");
    assert_eq!(fs::read_to_string(&path).expect("the old file"), "old");
    assert_eq!(entries(&locked), ["model.json"]);
}

/// The child of the test above: writes the file it is given (as an unprivileged user), asserts
/// that the write failed and prints the error on stderr. Ignored, so that it runs only when the
/// test above asks for it.
#[cfg(unix)]
#[test]
#[ignore = "run by atomic_write_in_a_read_only_directory_keeps_the_old_file as nobody"]
fn write_into_locked_directory_as_child() {
    let target = std::env::var_os(CHILD_TARGET).expect("started by the parent test");
    assert!(!is_root(), "the child must not run as root");
    let error = write_atomic(std::path::Path::new(&target), b"new")
        .expect_err("writing into a read-only directory fails");
    eprintln!("{error}");
}

/// Whether this process runs as root (whom file permissions do not stop).
#[cfg(unix)]
fn is_root() -> bool {
    use std::os::unix::fs::MetadataExt;
    // A file this process creates is owned by its effective user.
    let probe = tempfile::NamedTempFile::new().expect("a temporary file");
    probe.as_file().metadata().expect("metadata").uid() == 0
}

#[cfg(unix)]
#[test]
fn atomic_write_keeps_permissions_and_symbolic_links() {
    use std::os::unix::fs::PermissionsExt;
    let dir = dir();
    let path = dir.path().join("data.csv");
    fs::write(&path, "old").expect("the old file");
    fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).expect("permissions");
    write_atomic(&path, b"new").expect("writing");
    let mode = fs::metadata(&path).expect("metadata").permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);

    let link = dir.path().join("latest.csv");
    std::os::unix::fs::symlink("data.csv", &link).expect("a link");
    write_atomic(&link, b"through the link").expect("writing through a link");
    assert!(
        fs::symlink_metadata(&link)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read(&path).expect("reading"), b"through the link");
    assert_eq!(entries(dir.path()), ["data.csv", "latest.csv"]);
}

#[test]
fn a_failed_write_names_the_path_once_and_leaves_nothing() {
    let d = dir();
    let path = d.path().join("missing-folder").join("out.csv");
    let error = write_csv(&path, &["a"], &[&[1.0, 2.0]]).unwrap_err();
    let message = error.to_string();
    let shown = path.display().to_string();
    assert_eq!(message.matches(&shown).count(), 1, "{message}");
    assert!(matches!(error, DataError::Write { .. }), "{error:?}");
    assert!(entries(d.path()).is_empty(), "{:?}", entries(d.path()));
}

/// A pair of files: both replaced when both can be written; when the second cannot (a
/// directory at its path, a missing folder), neither is, whichever existed before, and no
/// temporary file is left (`learn`'s state and drive files once parted on a full disk).
#[test]
fn a_pair_is_written_whole_or_not_at_all() {
    let dir = dir();
    let (state, drive) = (
        dir.path().join("out.learn.json"),
        dir.path().join("out.csv"),
    );
    fs::write(&state, "old state").expect("the old state");
    fs::write(&drive, "old drive").expect("the old drive");
    write_atomic_pair((&state, b"new state"), (&drive, b"new drive")).expect("both written");
    assert_eq!(fs::read_to_string(&state).unwrap(), "new state");
    assert_eq!(fs::read_to_string(&drive).unwrap(), "new drive");
    assert_eq!(entries(dir.path()), ["out.csv", "out.learn.json"]);

    fs::create_dir(dir.path().join("folder")).unwrap();
    let refused = [
        dir.path().join("folder"),
        dir.path().join("missing/out.csv"),
    ];
    for second in &refused {
        let error = write_atomic_pair((&state, b"third state"), (second, b"third drive"))
            .expect_err("the second cannot be written");
        assert_contains(&error.to_string(), &[&second.display().to_string()]);
        assert_eq!(
            fs::read_to_string(&state).unwrap(),
            "new state",
            "first kept"
        );
        // The first refused in turn: the second (an existing file) kept too.
        let error = write_atomic_pair((second, b"third drive"), (&drive, b"third state"))
            .expect_err("the first cannot be written");
        assert_contains(&error.to_string(), &[&second.display().to_string()]);
        assert_eq!(
            fs::read_to_string(&drive).unwrap(),
            "new drive",
            "second kept"
        );
    }
    assert_eq!(entries(dir.path()), ["folder", "out.csv", "out.learn.json"]);
}
