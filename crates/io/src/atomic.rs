//! Files written atomically: a reader (or a crash) sees either the old file or the new one,
//! never a partial file.
//!
//! [`write_atomic`] writes the contents to a temporary file in the target's directory (the
//! same file system, so the final rename is atomic), flushes it to disk, renames it over the
//! target and flushes the directory. Model files, results and figures all go through it.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// How many bytes of the target's name the temporary file's name keeps, so that it stays
/// within file-name length limits.
const NAME_PREFIX_LIMIT: usize = 64;

/// Writes `contents` to `path` atomically: to a temporary file `.NAME.XXXXXX.tmp` in the same
/// directory, flushed to disk (`fsync`), then renamed over `path`, and the directory flushed.
///
/// - On any error the file at `path` is left as it was and the temporary file is removed.
/// - An existing file keeps its permissions; a new file gets the usual permissions for new
///   files (`0o666` less the umask on Unix).
/// - When `path` is a symbolic link, the file it points to is replaced and the link kept.
/// - A directory at `path` is refused ([`io::ErrorKind::IsADirectory`]).
///
/// Errors name the path once: `could not write out/model.json: the folder out does not exist`;
/// callers that add context should not repeat it.
pub fn write_atomic(path: &Path, contents: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |out| out.write_all(contents))
}

/// Like [`write_atomic`], for contents produced by a writer (an encoder, a long CSV): `write`
/// writes them to the temporary file (buffered); when it returns an error, the file at `path`
/// is left as it was, the temporary file is removed and the error returned with the path.
pub fn write_atomic_with<F>(path: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let context = |error: io::Error| {
        io::Error::new(
            error.kind(),
            format!("could not write {}: {error}", path.display()),
        )
    };
    let target = resolve_link(path).map_err(context)?;
    write_replacing(&target, write).map_err(context)
}

/// The file a symbolic link points to (following chains of links), or `path` itself.
fn resolve_link(path: &Path) -> io::Result<PathBuf> {
    let mut target = path.to_owned();
    // A bound on the chain, as the operating system has one (ELOOP).
    for _ in 0..40 {
        match fs::symlink_metadata(&target) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = fs::read_link(&target)?;
                target = match target.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(target),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Writes `first` and then `second` (each a path and its contents) as [`write_atomic`] does,
/// both temporary files written and flushed before either is renamed: an error while writing
/// them (a full disk, a folder that does not exist, a directory at a path) leaves both files
/// as they were. Only a crash between the two renames can leave the first replaced and the
/// second not (callers that pair files check them against each other, as `learn` does).
pub fn write_atomic_pair(first: (&Path, &[u8]), second: (&Path, &[u8])) -> io::Result<()> {
    fn context(path: &Path, error: io::Error) -> io::Error {
        io::Error::new(
            error.kind(),
            format!("could not write {}: {error}", path.display()),
        )
    }
    let prepare = |(path, contents): (&Path, &[u8])| {
        resolve_link(path)
            .and_then(|target| Prepared::new(target, |out| out.write_all(contents)))
            .map_err(|e| context(path, e))
    };
    let (a, b) = (prepare(first)?, prepare(second)?);
    a.commit().map_err(|e| context(first.0, e))?;
    b.commit().map_err(|e| context(second.0, e))
}

fn write_replacing<F>(target: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    Prepared::new(target.to_owned(), write)?.commit()
}

/// A temporary file written and flushed beside its target, not yet renamed over it (dropped,
/// it is removed).
struct Prepared {
    temporary: tempfile::NamedTempFile,
    target: PathBuf,
    dir: PathBuf,
}

impl Prepared {
    /// Renames the temporary file over the target and flushes the directory.
    fn commit(self) -> io::Result<()> {
        self.temporary
            .persist(&self.target)
            .map_err(|error| error.error)?;
        sync_directory(&self.dir)
    }

    fn new<F>(target: PathBuf, write: F) -> io::Result<Prepared>
    where
        F: FnOnce(&mut dyn Write) -> io::Result<()>,
    {
        let target = target.as_path();
        let file_name = target.file_name().ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                "the path does not end in a file name",
            )
        })?;
        let dir = match target.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let existing = match fs::metadata(target) {
            Ok(meta) if meta.is_dir() => {
                return Err(io::Error::new(
                    io::ErrorKind::IsADirectory,
                    "it is a directory; give a file name",
                ));
            }
            Ok(meta) => Some(meta.permissions()),
            Err(error) if error.kind() == io::ErrorKind::NotFound => None,
            Err(error) => return Err(error),
        };

        let name = file_name.to_string_lossy();
        let mut cut = name.len().min(NAME_PREFIX_LIMIT);
        while !name.is_char_boundary(cut) {
            cut -= 1;
        }
        let prefix = format!(".{}.", &name[..cut]);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        if existing.is_none() {
            use std::os::unix::fs::PermissionsExt;
            // Applied at creation, so the umask narrows it as for any new file.
            builder.permissions(fs::Permissions::from_mode(0o666));
        }
        // Dropping `temporary` on any early return removes the temporary file.
        let mut temporary = builder
            .tempfile_in(dir)
            .map_err(|error| temporary_file_error(dir, error))?;
        if let Some(permissions) = existing {
            temporary.as_file().set_permissions(permissions)?;
        }
        {
            let mut buffered = io::BufWriter::new(temporary.as_file_mut());
            write(&mut buffered)?;
            buffered.flush()?;
        }
        temporary.as_file().sync_all()?;
        Ok(Prepared {
            temporary,
            target: target.to_owned(),
            dir: dir.to_owned(),
        })
    }
}

/// Why the temporary file could not be created, said in terms of the target's folder (the
/// temporary file's own name means nothing to the reader, and the caller names the target).
fn temporary_error_message(dir: &Path, error: &io::Error) -> String {
    match error.kind() {
        io::ErrorKind::NotFound => format!("the folder {} does not exist", dir.display()),
        io::ErrorKind::PermissionDenied => format!(
            "no permission to create files in the folder {}",
            dir.display()
        ),
        _ => {
            // tempfile appends ` at path "<the temporary file>"`; drop it.
            let text = error.to_string();
            let reason = text
                .split(" at path \"")
                .next()
                .unwrap_or(&text)
                .to_string();
            format!(
                "cannot create a temporary file in the folder {}: {reason}",
                dir.display()
            )
        }
    }
}

fn temporary_file_error(dir: &Path, error: io::Error) -> io::Error {
    io::Error::new(error.kind(), temporary_error_message(dir, &error))
}

/// Flushes a directory entry change (the rename) to disk where the platform allows it.
#[cfg(unix)]
fn sync_directory(dir: &Path) -> io::Result<()> {
    fs::File::open(dir)?.sync_all()
}

/// Flushes a directory entry change (the rename) to disk where the platform allows it.
#[cfg(not(unix))]
fn sync_directory(_dir: &Path) -> io::Result<()> {
    Ok(())
}
