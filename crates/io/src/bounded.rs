//! Reading a user's file with a bound on its size, checked while reading: a file's size as
//! the file system reports it is not enough (`/dev/zero`, a named pipe or `/proc` files report
//! 0 and never end, or end later than they said).

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// What [`read_at_most`] found.
#[derive(Debug)]
pub enum Bounded {
    /// The whole file, at most the limit.
    Whole(Vec<u8>),
    /// The file holds more than the limit; reading stopped there.
    TooLarge,
}

/// Reads `path` whole when it holds at most `limit` bytes; never allocates much more than
/// `limit`, whatever the file reports.
pub fn read_at_most(path: &Path, limit: u64) -> io::Result<Bounded> {
    let file = File::open(path)?;
    if file
        .metadata()
        .is_ok_and(|m| m.is_file() && m.len() > limit)
    {
        return Ok(Bounded::TooLarge);
    }
    let expected = file
        .metadata()
        .map(|m| m.len().min(limit))
        .unwrap_or(0)
        .try_into()
        .unwrap_or(0usize);
    let mut bytes = Vec::with_capacity(expected);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        Ok(Bounded::TooLarge)
    } else {
        Ok(Bounded::Whole(bytes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_and_large_files_stop_at_the_limit() {
        #[cfg(unix)]
        assert!(matches!(
            read_at_most(Path::new("/dev/zero"), 1000).unwrap(),
            Bounded::TooLarge
        ));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        std::fs::write(&path, [7u8; 100]).unwrap();
        assert!(matches!(
            read_at_most(&path, 99).unwrap(),
            Bounded::TooLarge
        ));
        match read_at_most(&path, 100).unwrap() {
            Bounded::Whole(bytes) => assert_eq!(bytes, [7u8; 100]),
            Bounded::TooLarge => panic!("100 bytes fit a limit of 100"),
        }
        assert_eq!(
            read_at_most(dir.path(), 100).unwrap_err().kind(),
            io::ErrorKind::IsADirectory
        );
    }
}
