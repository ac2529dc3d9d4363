//! The folder an operator names for log files that peers ask for.
//!
//! A peer may ask a server to write logs (the Auxiliary_Logger's requests, the remote log
//! names a client sends when it connects). VRPN has no authentication, so a name from a peer
//! is never a path: it must be a plain file name, and it is created inside the operator's
//! folder, never over an existing file. Anything else is refused with a reason the peer can
//! be told.

use std::fmt;
use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};

/// Longest file name accepted from a peer (bytes).
pub const MAX_NAME_LEN: usize = 255;

/// Where logs requested by peers are written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogFolder {
    dir: PathBuf,
}

/// Why a requested log name was refused.
#[derive(Debug)]
pub enum Refusal {
    /// Not UTF-8, empty, `.` or `..`, or longer than [`MAX_NAME_LEN`].
    BadName(String),
    /// An absolute path.
    Absolute(String),
    /// A path with folders in it (`/`, `\`), `..` among them or not.
    NotPlain(String),
    /// A control character (NUL, newline, …) in the name.
    ControlCharacter(String),
    /// The file exists already; logs never overwrite.
    Exists(PathBuf),
    /// The folder refused the file (permissions, disk full, no such folder).
    Io(PathBuf, std::io::Error),
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::BadName(n) => write!(f, "{n:?} is not a usable file name"),
            Refusal::Absolute(n) => write!(
                f,
                "{n:?} is an absolute path: only a plain file name is accepted, written in the \
                 server's log folder"
            ),
            Refusal::NotPlain(n) => write!(
                f,
                "{n:?} names folders: only a plain file name is accepted, written in the \
                 server's log folder"
            ),
            Refusal::ControlCharacter(n) => {
                write!(f, "{n:?} contains a control character")
            }
            // The file name only: the folder is the operator's business, not the peer's.
            Refusal::Exists(p) => write!(f, "{:?} exists already (logs never overwrite)", leaf(p)),
            Refusal::Io(p, e) => write!(f, "cannot create {:?}: {e}", leaf(p)),
        }
    }
}

impl std::error::Error for Refusal {}

fn leaf(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Why a log folder cannot be used.
#[derive(Debug)]
pub enum FolderError {
    /// The path is not a folder.
    NotAFolder(PathBuf),
    /// The path cannot be read (no such folder, permissions).
    Io(PathBuf, std::io::Error),
}

impl fmt::Display for FolderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FolderError::NotAFolder(p) => write!(f, "{}: not a folder", p.display()),
            FolderError::Io(p, e) => write!(f, "{}: {e}", p.display()),
        }
    }
}

impl std::error::Error for FolderError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            FolderError::Io(_, e) => Some(e),
            FolderError::NotAFolder(_) => None,
        }
    }
}

impl LogFolder {
    /// A folder for peers' logs; it must exist and be a folder.
    pub fn new(dir: impl Into<PathBuf>) -> Result<LogFolder, FolderError> {
        let dir = dir.into();
        match std::fs::metadata(&dir) {
            Ok(m) if m.is_dir() => Ok(LogFolder { dir }),
            Ok(_) => Err(FolderError::NotAFolder(dir)),
            Err(e) => Err(FolderError::Io(dir, e)),
        }
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Checks a name a peer sent: a plain file name (no folder, not absolute, not `.`/`..`,
    /// no control character, UTF-8, at most [`MAX_NAME_LEN`] bytes). Returns it as text.
    pub fn check_name(name: &[u8]) -> Result<&str, Refusal> {
        let shown = || String::from_utf8_lossy(name).into_owned();
        let Ok(text) = std::str::from_utf8(name) else {
            return Err(Refusal::BadName(shown()));
        };
        if text.is_empty() || text == "." || text == ".." || name.len() > MAX_NAME_LEN {
            return Err(Refusal::BadName(shown()));
        }
        if text.starts_with('/') || text.starts_with('\\') || text.contains(':') {
            // `C:` and `\\host` are absolute elsewhere; refuse them everywhere.
            return Err(Refusal::Absolute(shown()));
        }
        if text.contains('/') || text.contains('\\') {
            return Err(Refusal::NotPlain(shown()));
        }
        if text.chars().any(char::is_control) {
            return Err(Refusal::ControlCharacter(shown()));
        }
        Ok(text)
    }

    /// Where `name` would be written, after [`check_name`](Self::check_name).
    pub fn resolve(&self, name: &[u8]) -> Result<PathBuf, Refusal> {
        let plain = Self::check_name(name)?;
        Ok(self.dir.join(plain))
    }

    /// Creates the file `name` in the folder, never over an existing file (nor through a
    /// symbolic link planted under that name).
    pub fn create(&self, name: &[u8]) -> Result<(PathBuf, File), Refusal> {
        let path = self.resolve(name)?;
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(f) => Ok((path, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(Refusal::Exists(path)),
            Err(e) => Err(Refusal::Io(path, e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_folder(tag: &str) -> LogFolder {
        let dir = std::env::temp_dir().join(format!("vrpn-folder-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        LogFolder::new(&dir).unwrap()
    }

    #[test]
    fn plain_names_resolve_inside() {
        let f = temp_folder("plain");
        assert_eq!(f.resolve(b"run1.vrpn").unwrap(), f.path().join("run1.vrpn"));
        assert_eq!(f.resolve(b"..hidden").unwrap(), f.path().join("..hidden"));
    }

    #[test]
    fn paths_are_refused() {
        for bad in [
            &b"/etc/passwd"[..],
            b"../x.vrpn",
            b"a/../../x",
            b"sub/x.vrpn",
            b"..",
            b".",
            b"",
            b"C:\\x",
            b"\\\\host\\share",
            b"a\\b",
            b"x\0y",
            b"x\ny",
            b"\xff\xfe",
        ] {
            assert!(LogFolder::check_name(bad).is_err(), "{bad:?} accepted");
        }
        assert!(LogFolder::check_name(&[b'a'; MAX_NAME_LEN + 1]).is_err());
        assert!(matches!(
            LogFolder::check_name(b"/abs"),
            Err(Refusal::Absolute(_))
        ));
        assert!(matches!(
            LogFolder::check_name(b"../up"),
            Err(Refusal::NotPlain(_))
        ));
    }

    #[test]
    fn existing_files_and_links_are_refused() {
        let f = temp_folder("exists");
        let (p, _) = f.create(b"one.vrpn").unwrap();
        assert!(p.exists());
        assert!(matches!(f.create(b"one.vrpn"), Err(Refusal::Exists(_))));
        let target = f.path().join("target");
        std::os::unix::fs::symlink(&target, f.path().join("link.vrpn")).unwrap();
        assert!(matches!(f.create(b"link.vrpn"), Err(Refusal::Exists(_))));
        assert!(!target.exists());
        let _ = std::fs::remove_dir_all(f.path());
    }

    #[test]
    fn folder_must_exist() {
        assert!(LogFolder::new("/nonexistent/vrpn/folder").is_err());
    }
}
