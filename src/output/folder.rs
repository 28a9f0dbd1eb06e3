//! The result-folder protocol: the one place where raycost creates, replaces and publishes files that
//! a user keeps (run, resume, merge, bench, render, report all write through it).
//!
//! Modelled on git's lockfiles and SQLite's atomic commit:
//!
//! - **One writer per result.** [`Lock::acquire`] takes `DIR/STEM.lock` for the whole run: the file
//!   is created (never through a symlink), locked with `flock(2)` and holds the holder's pid, host,
//!   boot id, the pid's start time and the command. A second writer is refused naming the first. A
//!   lock left by a process that died (a `kill -9`, a node reboot) is *stale*: on the same host the
//!   kernel has released its `flock`, so it is taken over and named ([`Lock::took_over`]), whether
//!   its pid is gone or was reused by another process. A lock written on **another host** cannot be
//!   checked from here (its pid means nothing here, and `flock` is not coherent on every network
//!   file system), so it is refused with its host and pid and the file to delete once that run is
//!   known to be gone.
//! - **New files are new.** [`create_new`] opens with `O_CREAT | O_EXCL`, which never follows a
//!   symlink (not even a dangling one); [`open_existing`] opens with `O_NOFOLLOW` and accepts only a
//!   regular file. So a symlink planted at a `.partial` or temporary path cannot redirect a write
//!   outside the folder.
//! - **Whole files or none.** [`write_atomic`] writes a fresh temporary file beside the target,
//!   fsyncs it, renames it over the target and fsyncs the folder: a reader (or a resume after a
//!   crash or a full disk) sees the old content or the new, never a truncated mix. Nothing is ever
//!   rewritten in place.
//! - **Publication with one commit point.** [`publish`] renames several finished files into place;
//!   the last one (a run's main table) is the commit point: the old one is taken down first and the
//!   new one appears last, so its presence means every other file of the set is in place. A failure
//!   part-way leaves the sources (a run's `.partial` files) where a `--resume` finds them.
//!
//! What this cannot give: two readers that open several files of a folder while a writer publishes
//! may see one file old and the next new (POSIX has no multi-file transaction); read the main table
//! last, as `raycost merge` and `report` do.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use super::meta::host_name;
use crate::error::{file_kind, OutputError};

/// Creates `path` as a new, empty file opened for writing; fails if anything exists there, a
/// symlink included (`O_CREAT | O_EXCL` never follows one).
pub fn create_new(path: &Path) -> io::Result<File> {
    OpenOptions::new().write(true).create_new(true).open(path)
}

/// Opens the existing regular file `path` to read (and, with `append`, to append), never through a
/// symlink: a symlink, a folder, a FIFO or a device there is an error naming what it is.
pub fn open_existing(path: &Path, append: bool) -> io::Result<File> {
    let mut o = OpenOptions::new();
    o.read(true);
    if append {
        o.append(true);
    }
    nofollow(&mut o);
    let f = o.open(path).map_err(|e| {
        if fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
            io::Error::other(format!(
                "is a symlink; result files are never written through one ({e})"
            ))
        } else {
            e
        }
    })?;
    let kind = f.metadata()?.file_type();
    if !kind.is_file() {
        return Err(io::Error::other(format!(
            "is {}, not a regular file",
            file_kind(&kind)
        )));
    }
    Ok(f)
}

#[cfg(target_os = "linux")]
fn nofollow(o: &mut OpenOptions) {
    use std::os::unix::fs::OpenOptionsExt;
    o.custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
}

#[cfg(not(target_os = "linux"))]
fn nofollow(_: &mut OpenOptions) {}

/// Removes `path` if it exists (a symlink is removed itself, never its target).
pub fn remove_if_exists(path: &Path) -> io::Result<()> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Flushes a folder's entries (new names, renames) to disk. File systems that cannot fsync a folder
/// (some network and FUSE ones answer EINVAL) are taken at their word.
pub fn sync_dir(dir: &Path) -> io::Result<()> {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    match File::open(dir).and_then(|d| d.sync_all()) {
        Err(e) if e.raw_os_error() == Some(22) => Ok(()),
        other => other,
    }
}

fn parent(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// A temporary file beside `path`, created new: `.NAME.tmp-PID-N` (a name already taken, a planted
/// symlink included, is skipped).
fn temporary(path: &Path) -> io::Result<(PathBuf, File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = parent(path).join(format!(".{name}.tmp-{}-{n}", std::process::id()));
        match create_new(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && n < 1_000_000 => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Removes the temporary files a killed writer left beside `targets` (`.NAME.tmp-PID-N`). Call it
/// holding the lock of the result the targets belong to: no live writer can own them then.
pub fn remove_stale_temporaries(targets: &[PathBuf]) -> io::Result<()> {
    let mut by_dir: Vec<(&Path, Vec<String>)> = Vec::new();
    for t in targets {
        let Some(name) = t.file_name() else { continue };
        let prefix = format!(".{}.tmp-", name.to_string_lossy());
        match by_dir.iter_mut().find(|(d, _)| *d == parent(t)) {
            Some((_, p)) => p.push(prefix),
            None => by_dir.push((parent(t), vec![prefix])),
        }
    }
    for (dir, prefixes) in by_dir {
        let Ok(entries) = fs::read_dir(dir) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if prefixes.iter().any(|p| name.starts_with(p.as_str())) {
                remove_if_exists(&e.path())?;
            }
        }
    }
    Ok(())
}

/// A finished temporary file (written and fsynced), not yet in place: [`Staged::commit`] renames it,
/// dropping it removes it.
#[derive(Debug)]
pub struct Staged {
    tmp: Option<PathBuf>,
    dest: PathBuf,
}

impl Staged {
    /// Where it goes.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Renames it over its destination (and fsyncs the folder).
    pub fn commit(mut self) -> io::Result<()> {
        let tmp = self.tmp.take().expect("a staged file is committed once");
        let r = fs::rename(&tmp, &self.dest).and_then(|()| sync_dir(parent(&self.dest)));
        if r.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        r
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(t) = self.tmp.take() {
            let _ = fs::remove_file(t);
        }
    }
}

/// Writes a new temporary file beside `path` with what `write` puts in it and fsyncs it; nothing at
/// `path` changes until [`Staged::commit`]. Creates the folder if needed.
pub fn stage_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> anyhow::Result<()>,
) -> anyhow::Result<Staged> {
    use anyhow::Context as _;
    fs::create_dir_all(parent(path))
        .with_context(|| format!("cannot create {}", parent(path).display()))?;
    let (tmp, f) = temporary(path)
        .with_context(|| format!("cannot create a temporary file beside {}", path.display()))?;
    let staged = Staged {
        tmp: Some(tmp),
        dest: path.to_path_buf(),
    };
    let mut w = BufWriter::new(f);
    write(&mut w).with_context(|| format!("cannot write {}", path.display()))?;
    w.flush()
        .and_then(|()| w.get_ref().sync_all())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(staged)
}

/// [`stage_with`] for bytes in memory.
pub fn stage(path: &Path, bytes: &[u8]) -> io::Result<Staged> {
    stage_with(path, |w| Ok(w.write_all(bytes)?)).map_err(|e| {
        match e.chain().find_map(|c| c.downcast_ref::<io::Error>()) {
            Some(io) => io::Error::new(io.kind(), format!("{e:#}")),
            None => io::Error::other(format!("{e:#}")),
        }
    })
}

/// Replaces `path` by `bytes` as a whole: a new temporary file, fsynced, renamed over it, the folder
/// fsynced. On any failure `path` is as it was and no temporary is left.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    stage(path, bytes)?.commit()
}

/// [`write_atomic`] with a streaming writer (an image encoder).
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    use anyhow::Context as _;
    stage_with(path, write)?
        .commit()
        .with_context(|| format!("cannot move {} into place", path.display()))
}

/// Publishes finished files: renames each `(from, to)` in order (each in the same folder), the last
/// being the commit point. The last destination is removed first, so while the others are being
/// replaced the set reads as "not finished" rather than as a mix of an old and a new result. On a
/// failure the remaining sources stay where they are (a run's `.partial` files: `--resume` finds
/// them).
pub fn publish(moves: &[(PathBuf, PathBuf)]) -> io::Result<()> {
    let Some((_, commit)) = moves.last() else {
        return Ok(());
    };
    remove_if_exists(commit)?;
    let mut dirs: Vec<&Path> = Vec::new();
    for (from, to) in moves {
        fs::rename(from, to).map_err(|e| {
            let what = format!("cannot rename {} to {}: {e}", from.display(), to.display());
            io::Error::new(e.kind(), what)
        })?;
        if !dirs.contains(&parent(to)) {
            dirs.push(parent(to));
        }
    }
    for d in dirs {
        sync_dir(d)?;
    }
    Ok(())
}

/// [`publish`] for staged files (in order, the last the commit point); on a failure the temporaries
/// not yet moved are removed.
pub fn publish_staged(mut staged: Vec<Staged>) -> io::Result<()> {
    let moves: Vec<(PathBuf, PathBuf)> = staged
        .iter_mut()
        .filter_map(|s| Some((s.tmp.take()?, s.dest.clone())))
        .collect();
    let r = publish(&moves);
    if r.is_err() {
        for (tmp, _) in &moves {
            let _ = fs::remove_file(tmp);
        }
    }
    r
}

/// Renames `from` to `to` and fsyncs the folder.
pub fn rename(from: &Path, to: &Path) -> io::Result<()> {
    fs::rename(from, to)?;
    sync_dir(parent(to))
}

/// Who holds a lock: what `STEM.lock` records.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Holder {
    /// Its process id (meaningful on `host` only).
    pub pid: u32,
    /// The host it runs on.
    pub host: String,
    /// The host's boot id: a lock from before a reboot is stale whatever its pid.
    #[serde(default)]
    pub boot_id: String,
    /// When the process started, in clock ticks after boot (`/proc/PID/stat` field 22): a pid now
    /// used by another process has another start time.
    #[serde(default)]
    pub pid_start: u64,
    /// When it took the lock, RFC 3339 UTC.
    pub started: String,
    /// Its command line.
    #[serde(default)]
    pub command: String,
}

impl Holder {
    /// This process.
    fn current() -> Self {
        Self {
            pid: std::process::id(),
            host: host_name(),
            boot_id: boot_id(),
            pid_start: pid_start(std::process::id()).unwrap_or(0),
            started: super::time::now_rfc3339(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
        }
    }

    /// `pid P on host H since T (raycost …)`.
    pub fn describe(&self) -> String {
        let cmd = if self.command.is_empty() {
            String::new()
        } else {
            format!(": {}", self.command)
        };
        format!(
            "pid {} on host {} since {}{cmd}",
            self.pid, self.host, self.started
        )
    }

    /// On this host: whether the process that wrote the lock still runs, in words when it does
    /// not (gone, or its pid reused by a later process). `None` when it cannot be told from here.
    fn liveness_here(&self) -> Option<Result<(), String>> {
        if self.host != host_name() {
            return None;
        }
        if !self.boot_id.is_empty() && self.boot_id != boot_id() {
            return Some(Err("the host has rebooted since".into()));
        }
        match pid_start(self.pid) {
            None => Some(Err(format!("pid {} is no longer running", self.pid))),
            Some(s) if self.pid_start != 0 && s != self.pid_start => Some(Err(format!(
                "pid {} is now another process (its pid was reused)",
                self.pid
            ))),
            Some(_) => Some(Ok(())),
        }
    }
}

fn boot_id() -> String {
    fs::read_to_string("/proc/sys/kernel/random/boot_id")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// Field 22 of `/proc/PID/stat`: the process's start time in ticks after boot; `None` if no such
/// process (or no `/proc`).
fn pid_start(pid: u32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command (field 2) is in parentheses and may hold spaces: count fields after its ')'.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

/// The start of the refusal when the lock file cannot be created.
const UNWRITABLE: &str = "cannot create the lock file (is the folder writable?)";

/// Paths of the locks this process holds, for [`release_locks`] on Ctrl-C.
static HELD: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every lock file this process holds: for an exit that skips destructors (the Ctrl-C
/// handler's `process::exit`). The kernel drops the `flock` itself when the process ends.
pub fn release_locks() {
    if let Ok(held) = HELD.lock() {
        for p in held.iter() {
            let _ = fs::remove_file(p);
        }
    }
}

/// An exclusive lock on the result `DIR/STEM.*`, held until dropped (see the module documentation).
#[derive(Debug)]
pub struct Lock {
    path: PathBuf,
    file: Option<File>,
    took_over: Option<String>,
}

/// Whether this file system gave us an exclusive `flock`.
enum Flock {
    Held,
    Busy,
    Unsupported,
}

fn try_flock(f: &File) -> io::Result<Flock> {
    match f.try_lock() {
        Ok(()) => Ok(Flock::Held),
        Err(fs::TryLockError::WouldBlock) => Ok(Flock::Busy),
        Err(fs::TryLockError::Error(e))
            if matches!(e.raw_os_error(), Some(37 | 38 | 95)) /* ENOLCK, ENOSYS, EOPNOTSUPP */ =>
        {
            Ok(Flock::Unsupported)
        }
        Err(fs::TryLockError::Error(e)) => Err(e),
    }
}

#[cfg(unix)]
fn same_inode(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_inode(_: &fs::Metadata, _: &fs::Metadata) -> bool {
    true
}

impl Lock {
    /// The lock file of result `stem` in `dir`.
    pub fn path_of(dir: &Path, stem: &str) -> PathBuf {
        dir.join(format!("{stem}.lock"))
    }

    /// Takes the lock of result `stem` in `dir` (which must exist), or refuses with an
    /// [`OutputError`] (exit 2, nothing written) naming the run that holds it.
    pub fn acquire(dir: &Path, stem: &str) -> Result<Lock, OutputError> {
        let path = Self::path_of(dir, stem);
        let refuse = |m: String| OutputError::new(&path, m);
        for _ in 0..100 {
            let mut o = OpenOptions::new();
            o.read(true).write(true).create(true);
            nofollow(&mut o);
            let mut f = o.open(&path).map_err(|e| {
                if fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
                    refuse("is a symlink; a lock file is never followed: remove it".into())
                } else {
                    refuse(format!("{UNWRITABLE}: {e}"))
                }
            })?;
            let meta = f.metadata().map_err(|e| refuse(e.to_string()))?;
            if !meta.is_file() {
                return Err(refuse(format!(
                    "is {}, not a lock file: remove it",
                    file_kind(&meta.file_type())
                )));
            }
            let flock = try_flock(&f).map_err(|e| refuse(format!("cannot lock it: {e}")))?;
            let mut text = String::new();
            let _ = f.read_to_string(&mut text);
            let then: Option<Holder> = toml::from_str(&text).ok();
            if let Flock::Busy = flock {
                let who = then.map_or_else(
                    || "another process (it has not written its name yet)".to_string(),
                    |h| h.describe(),
                );
                return Err(refuse(format!(
                    "a run is in progress on this result: {who}. Wait for it to finish (or stop \
                     it), then run again; two writers would corrupt the tables"
                )));
            }
            // The file may have been removed (and another created) between our open and our lock:
            // then we hold a lock on a name nobody sees. Start over.
            match fs::symlink_metadata(&path) {
                Ok(now) if same_inode(&now, &meta) => {}
                _ => continue,
            }
            let took_over = match (&then, flock) {
                (None, _) if text.trim().is_empty() => None,
                (None, _) => Some("an unreadable lock file (left by a crash)".to_string()),
                (Some(h), flock) => match (h.liveness_here(), flock) {
                    (None, _) => {
                        return Err(refuse(format!(
                            "a run holds this result on another host: {}. raycost can tell \
                             whether a lock's holder still runs only on the host that holds it. \
                             If that run has ended (its node failed), delete {} and run again",
                            h.describe(),
                            path.display()
                        )))
                    }
                    (Some(Ok(())), Flock::Unsupported) => {
                        return Err(refuse(format!(
                            "a run is in progress on this result: {}. Wait for it to finish \
                             (or stop it), then run again",
                            h.describe()
                        )))
                    }
                    (Some(Ok(())), _) => Some(format!(
                        "a stale lock of {} (it no longer holds the lock)",
                        h.describe()
                    )),
                    (Some(Err(why)), _) => {
                        Some(format!("a stale lock of {} ({why})", h.describe()))
                    }
                },
            };
            let mine = toml::to_string(&Holder::current()).expect("a holder serialises");
            let text = format!(
                "# raycost: a run is writing this result. Delete only if that process is gone.\n{mine}"
            );
            let written = f
                .set_len(0)
                .and_then(|()| f.rewind())
                .and_then(|()| f.write_all(text.as_bytes()))
                .and_then(|()| f.sync_all());
            if let Err(e) = written {
                // Still holding the flock: nobody else can be using this file. Leave no lock.
                let _ = fs::remove_file(&path);
                return Err(refuse(format!("cannot write the lock file: {e}")));
            }
            if let Ok(mut held) = HELD.lock() {
                held.push(path.clone());
            }
            return Ok(Lock {
                path,
                file: Some(f),
                took_over: took_over.map(|w| format!("took over {w}")),
            });
        }
        Err(refuse(
            "the lock file keeps being replaced by other processes; try again".into(),
        ))
    }

    /// [`Lock::acquire`] for a reader (`raycost merge` reading shards): in a folder this process
    /// cannot write (an archive of results), nobody it could race with writes either, and `None`
    /// comes back.
    pub fn acquire_if_writable(dir: &Path, stem: &str) -> Result<Option<Lock>, OutputError> {
        match Self::acquire(dir, stem) {
            Ok(l) => Ok(Some(l)),
            Err(e) if e.message.starts_with(UNWRITABLE) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A note when the lock was taken over from a process that died holding it: what it was and why
    /// it was judged stale.
    pub fn took_over(&self) -> Option<String> {
        self.took_over
            .as_ref()
            .map(|w| format!("{}: {w}", self.path.display()))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // Remove the name while still holding the flock, so that nobody takes a lock on a file
        // that is about to disappear (they re-check the inode after locking).
        if let Some(f) = self.file.take() {
            if let (Ok(now), Ok(ours)) = (fs::symlink_metadata(&self.path), f.metadata()) {
                if same_inode(&now, &ours) {
                    let _ = fs::remove_file(&self.path);
                }
            }
            drop(f);
        }
        if let Ok(mut held) = HELD.lock() {
            held.retain(|p| p != &self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_naming_the_first() {
        let d = tempfile::tempdir().expect("tempdir");
        let first = Lock::acquire(d.path(), "x").expect("first");
        assert!(first.took_over().is_none());
        let e = Lock::acquire(d.path(), "x").expect_err("second");
        assert!(
            e.message.contains("in progress")
                && e.message.contains(&format!("pid {}", std::process::id())),
            "{e}"
        );
        // Another result in the same folder (another shard) is not blocked.
        let other = Lock::acquire(d.path(), "x.shard-1-of-2").expect("another stem");
        drop(other);
        drop(first);
        assert!(
            !d.path().join("x.lock").exists(),
            "released locks are removed"
        );
        Lock::acquire(d.path(), "x").expect("free again");
    }

    /// A lock file left by a process that is gone (here: a pid that does not exist, and one reused
    /// by this very process with another start time) is taken over and named.
    #[test]
    fn stale_locks_on_this_host_are_taken_over_and_named() {
        let d = tempfile::tempdir().expect("tempdir");
        let me = Holder::current();
        let gone = Holder {
            pid: u32::MAX - 7,
            ..me.clone()
        };
        let reused = Holder {
            pid_start: me.pid_start + 1,
            ..me.clone()
        };
        for (h, why) in [(gone, "no longer running"), (reused, "pid was reused")] {
            fs::write(d.path().join("x.lock"), toml::to_string(&h).expect("toml")).expect("write");
            let l = Lock::acquire(d.path(), "x").expect("stale lock taken over");
            let note = l.took_over().expect("a note");
            assert!(note.contains("stale lock") && note.contains(why), "{note}");
        }
    }

    #[test]
    fn a_lock_of_another_host_is_refused_with_what_to_delete() {
        let d = tempfile::tempdir().expect("tempdir");
        let h = Holder {
            host: "some-other-node".into(),
            ..Holder::current()
        };
        fs::write(d.path().join("x.lock"), toml::to_string(&h).expect("toml")).expect("write");
        let e = Lock::acquire(d.path(), "x").expect_err("refused");
        assert!(
            e.message.contains("some-other-node") && e.message.contains("delete"),
            "{e}"
        );
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_are_never_followed() {
        let d = tempfile::tempdir().expect("tempdir");
        let outside = d.path().join("outside");
        fs::write(&outside, "keep").expect("write");
        let link = d.path().join("x.csv.partial");
        std::os::unix::fs::symlink(&outside, &link).expect("symlink");
        assert!(create_new(&link).is_err());
        let e = open_existing(&link, true).expect_err("refused");
        assert!(e.to_string().contains("symlink"), "{e}");
        // An atomic write replaces the link itself, never its target.
        write_atomic(&link, b"new").expect("write");
        assert_eq!(fs::read_to_string(&outside).expect("read"), "keep");
        assert!(!fs::symlink_metadata(&link)
            .expect("meta")
            .file_type()
            .is_symlink());
        // A symlink at the lock path is refused.
        std::os::unix::fs::symlink(&outside, d.path().join("y.lock")).expect("symlink");
        assert!(Lock::acquire(d.path(), "y").is_err());
        assert_eq!(fs::read_to_string(&outside).expect("read"), "keep");
    }

    #[test]
    fn publish_puts_the_commit_point_last_and_leaves_no_temporary() {
        let d = tempfile::tempdir().expect("tempdir");
        let p = |n: &str| d.path().join(n);
        fs::write(p("a.csv"), "old").expect("write");
        fs::write(p("a.csv.partial"), "new").expect("write");
        fs::write(p("a.meta.toml.partial"), "meta").expect("write");
        publish(&[
            (p("a.meta.toml.partial"), p("a.meta.toml")),
            (p("a.csv.partial"), p("a.csv")),
        ])
        .expect("publish");
        assert_eq!(fs::read_to_string(p("a.csv")).expect("read"), "new");
        // A failed publication (a source missing) has taken the old commit point down first.
        fs::write(p("b.csv"), "old").expect("write");
        assert!(publish(&[
            (p("missing"), p("b.meta.toml")),
            (p("b.csv.partial"), p("b.csv"))
        ])
        .is_err());
        assert!(!p("b.csv").exists());
        let names: Vec<String> = fs::read_dir(d.path())
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");
    }
}
