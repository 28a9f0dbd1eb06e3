//! One error type for the whole tool, and the exit code each kind of failure gets.
//!
//! | variant | exit | meaning |
//! |---|---|---|
//! | [`Error::Input`] | 2 | bad input: a spec, scene, OBJ, AFF or points file, located by [`InputError`] |
//! | [`Error::Refused`] | 2 | the output location is the user's to fix; nothing was written ([`OutputError`]) |
//! | [`Error::Usage`] | 2 | a flag value clap could not judge |
//! | [`Error::CheckFailed`] | 1 | a built-in check failed (an engine disagreed with brute force, an incremental frame with a full recalculation); the tables were kept as evidence |
//! | [`Error::Internal`] | 1 | anything else (I/O failure while writing, a bug reported as an error) |
//! | [`Error::Interrupted`] | 130 | Ctrl-C: finished points were kept; the message says how to resume |
//!
//! A panic exits 101 and an abort (allocation failure) 134; both are bugs, since every input is
//! refused with exit 2 before anything large is allocated.
//!
//! Every input problem, whatever file it is in, is one [`InputError`]: file, line and column, dotted
//! key, message — printed as `FILE:LINE:COL: KEY: what is wrong (what is allowed)` (pbrt-v4's
//! `FileLoc`, ripgrep's `globset::Error { glob, kind }`). Module boundaries return typed errors, never
//! `String`, so the exit code cannot be lost by flattening an error to text.

use std::fmt;

/// A problem with an input, located as precisely as the input allows.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct InputError {
    /// The file at fault (a spec, a scene, an OBJ, an AFF, a points CSV), or the `--set` flag.
    pub file: String,
    /// 1-based line and column, when known.
    pub at: Option<(usize, usize)>,
    /// The dotted key (or directive) at fault, when known.
    pub key: Option<String>,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl InputError {
    /// An error about `file` as a whole.
    pub fn new(file: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            at: None,
            key: None,
            message: message.into(),
        }
    }

    /// The same error at line and column `at`.
    pub fn at(mut self, at: Option<(usize, usize)>) -> Self {
        self.at = at;
        self
    }

    /// The same error naming dotted key `key`.
    pub fn key(mut self, key: impl Into<String>) -> Self {
        self.key = Some(key.into());
        self
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some((l, c)) = self.at {
            write!(f, ":{l}:{c}")?;
        }
        if let Some(k) = &self.key {
            write!(f, ": {k}")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// A refusal about the output location (a result that exists, a folder that is not writable, shards
/// that do not fit): the user's to fix, and nothing was written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct OutputError {
    /// The file or folder at fault.
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl OutputError {
    /// A refusal about `path`.
    pub fn new(path: &std::path::Path, message: impl Into<String>) -> Self {
        Self {
            path: path.display().to_string(),
            message: message.into(),
        }
    }
}

/// What a file that is not a regular file is, in words (for messages about special files).
pub fn file_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
    }
    if t.is_dir() {
        "a folder"
    } else if t.is_symlink() {
        "a symlink"
    } else if t.is_file() {
        "a regular file"
    } else {
        "a special file"
    }
}

/// Whether `path` is an input file raycost can use: an existing regular file (a symlink to one is
/// fine). Scenes, OBJ meshes, AFF includes and points files are read twice — once to load, once to
/// hash for the metadata that `--resume` and `raycost merge` check — so a FIFO, `/dev/stdin`, a
/// socket or a device (`/dev/zero` never ends) is refused by what it is, never called missing.
/// `Err` holds the reason, to follow the path: "no such file", "is a folder, …", "is a FIFO …".
pub fn regular_input(path: &std::path::Path) -> std::result::Result<(), String> {
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err("no such file".into()),
        Err(e) => Err(format!("cannot read: {e}")),
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) if m.is_dir() => Err("is a folder, not a file".into()),
        Ok(m) => Err(format!(
            "is {}, not a regular file: an input is read twice (to load it, and to hash it for \
             the metadata --resume and merge check), so save it to a regular file first",
            file_kind(&m.file_type())
        )),
    }
}

/// A value that is out of range or inconsistent, said in words; the caller locates it (a spec key, a
/// line of a scene file, a metadata file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct Invalid(pub String);

impl From<String> for Invalid {
    fn from(s: String) -> Self {
        Invalid(s)
    }
}

impl From<&str> for Invalid {
    fn from(s: &str) -> Self {
        Invalid(s.to_string())
    }
}

/// Every way raycost can fail; the variant decides the exit code ([`Error::exit_code`]).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input (exit 2).
    #[error(transparent)]
    Input(#[from] InputError),
    /// A refused output location (exit 2).
    #[error(transparent)]
    Refused(#[from] OutputError),
    /// A bad flag value (exit 2).
    #[error("{0}")]
    Usage(String),
    /// A built-in check failed; the result files were kept as evidence (exit 1).
    #[error("{0}")]
    CheckFailed(String),
    /// Ctrl-C (exit 130): what was kept and the command that resumes.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// Anything else (exit 1).
    #[error(transparent)]
    Internal(anyhow::Error),
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// The process exit code: 2 for the user's input, 1 for failures, 130 for Ctrl-C, 0 for a
    /// closed pipe (`raycost theory … | head` is not a failure).
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Input(_) | Error::Refused(_) | Error::Usage(_) => 2,
            Error::CheckFailed(_) => 1,
            Error::Interrupted(_) => 130,
            Error::Internal(e) if is_broken_pipe(e) => 0,
            Error::Internal(_) => 1,
        }
    }

    /// A usage error.
    pub fn usage(message: impl Into<String>) -> Self {
        Error::Usage(message.into())
    }

    /// An internal error with a message.
    pub fn internal(message: impl fmt::Display) -> Self {
        Error::Internal(anyhow::anyhow!("{message}"))
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Internal code may use anyhow for context; a typed error it carries keeps its variant (so an input
/// error given context on its way up still exits 2).
impl From<anyhow::Error> for Error {
    fn from(e: anyhow::Error) -> Self {
        let e = match e.downcast::<Error>() {
            Ok(typed) => return typed,
            Err(e) => e,
        };
        let e = match e.downcast::<InputError>() {
            Ok(typed) => return Error::Input(typed),
            Err(e) => e,
        };
        match e.downcast::<OutputError>() {
            Ok(typed) => Error::Refused(typed),
            Err(e) => Error::Internal(e),
        }
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Internal(e.into())
    }
}

/// Context for internal failures, as anyhow's, keeping typed errors typed.
pub trait Context<T> {
    /// Adds context to an internal failure; input errors and refusals pass through unchanged (their
    /// message already names the file).
    fn context_with(self, f: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn context_with(self, f: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| match e.into() {
            Error::Internal(inner) => Error::Internal(inner.context(f())),
            other => other,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_follows_the_contract() {
        let e = InputError::new("x.toml", "got -1, expected > 0")
            .at(Some((3, 14)))
            .key("scene.radius");
        assert_eq!(
            e.to_string(),
            "x.toml:3:14: scene.radius: got -1, expected > 0"
        );
        assert_eq!(
            InputError::new("--set a=1", "unknown key").to_string(),
            "--set a=1: unknown key"
        );
    }

    #[test]
    fn the_variant_decides_the_exit_code() {
        assert_eq!(Error::from(InputError::new("f", "m")).exit_code(), 2);
        assert_eq!(
            Error::from(OutputError::new(std::path::Path::new("p"), "m")).exit_code(),
            2
        );
        assert_eq!(Error::usage("m").exit_code(), 2);
        assert_eq!(Error::CheckFailed("m".into()).exit_code(), 1);
        assert_eq!(Error::Interrupted("m".into()).exit_code(), 130);
        assert_eq!(Error::internal("m").exit_code(), 1);
        let pipe = std::io::Error::new(std::io::ErrorKind::BrokenPipe, "closed");
        assert_eq!(Error::from(pipe).exit_code(), 0);
    }

    #[test]
    fn context_keeps_input_errors_typed() {
        let r: std::result::Result<(), InputError> = Err(InputError::new("f", "m"));
        let e = r
            .context_with(|| "while loading".into())
            .expect_err("an error");
        assert_eq!(e.exit_code(), 2);
        let r: std::result::Result<(), std::io::Error> = Err(std::io::Error::other("disk"));
        let e = r.context_with(|| "writing x".into()).expect_err("an error");
        assert_eq!(format!("{e:#}"), "writing x: disk");
    }
}
