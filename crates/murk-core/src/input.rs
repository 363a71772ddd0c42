//! Opening input files: only regular files, checked before opening, since opening a FIFO blocks until
//! something writes to it and a device can be read for ever.

use crate::{Error, Result};
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;

/// `path` opened for reading, if it is a regular file (or a link to one).
pub fn open_input(path: &Path) -> Result<File> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let why = if meta.is_dir() {
        "is a directory"
    } else if !meta.is_file() {
        "is not a regular file (a device, FIFO or socket)"
    } else {
        return File::open(path).map_err(|e| Error::io(path, e));
    };
    Err(Error::io(
        path,
        std::io::Error::new(ErrorKind::InvalidInput, why),
    ))
}

/// The whole of the regular file `path`.
pub fn read_input(path: &Path) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    open_input(path)?
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_are_read() {
        let dir = std::env::temp_dir().join(format!("murk-core-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("a.txt");
        std::fs::write(&f, b"abc").unwrap();
        assert_eq!(read_input(&f).unwrap(), b"abc");
        let e = read_input(&dir).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        // A device would be read for ever; it is refused before it is opened.
        let e = read_input(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(
            e.starts_with("/dev/zero: ") && e.contains("not a regular file"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
