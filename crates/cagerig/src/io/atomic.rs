//! Replacing a file atomically: write a temporary file in the same directory, then rename.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::error::ParseError;

/// Writes `path` through `write`: the bytes go to a temporary file beside `path`, which is
/// flushed, synced and renamed over `path` only if `write` succeeded. On failure the temporary
/// file is removed and any previous `path` is left untouched. A missing parent folder is
/// created first, as the command line creates its output folders.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), ParseError> {
    let temp = temp_path(path);
    let result = (|| -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            create_folder(dir)?;
        }
        let file = File::create(&temp)?;
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&temp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&temp);
        ParseError::io(path, &e)
    })
}

/// Creates `dir` and its missing parents; when a file stands where a folder must be, the
/// error names that file.
pub(crate) fn create_folder(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| match dir.ancestors().find(|a| a.is_file()) {
        Some(file) => std::io::Error::new(
            std::io::ErrorKind::NotADirectory,
            format!("{} is a file, not a folder", file.display()),
        ),
        None => e,
    })
}

/// `dir/.name.tmp<pid>` beside the target.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let temp_name = format!(".{name}.tmp{}", std::process::id());
    match path.parent() {
        Some(dir) => dir.join(temp_name),
        None => PathBuf::from(temp_name),
    }
}

/// Reads a whole file, mapping the failure to [`ParseError::Io`].
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, ParseError> {
    std::fs::read(path).map_err(|e| ParseError::io(path, &e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_on_success_and_keeps_old_on_failure() {
        let dir = std::env::temp_dir().join(format!("cagerig_atomic_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        write_atomically(&path, |w| w.write_all(b"first")).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(matches!(err, ParseError::Io { .. }));
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "temp file left behind"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn creates_a_missing_parent_folder() {
        let dir = std::env::temp_dir().join(format!("cagerig_atomic_dirs_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("out/nested/a.txt");
        write_atomically(&path, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        // A parent that is a file is reported, naming the output.
        let blocked = dir.join("out/nested/a.txt/b.txt");
        let err = write_atomically(&blocked, |w| w.write_all(b"x")).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!(
                "{}: {} is a file, not a folder",
                blocked.display(),
                path.display()
            )
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
