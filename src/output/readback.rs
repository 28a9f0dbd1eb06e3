//! Reading a result table back — a run's `.partial` files on `--resume`, a shard on `raycost
//! merge` — with every row parsed and checked, never trusted.
//!
//! A table is valid when: it is a regular file (never read through a symlink); its header's first
//! column is `point` and, where the metadata recorded the table's columns, the header is exactly
//! those columns; every row has the header's number of fields, valid UTF-8, no NUL byte, and a
//! point index in its first field; the file ends with a newline.
//!
//! A *torn* row is what a write cut short leaves (a kill, a full disk, a crash that zero-fills the
//! last block): bytes after the last newline, a NUL-filled tail, or a last row that fails the checks
//! above. Only the last row can be torn, since rows are appended one write at a time. With
//! [`Torn::DropLast`] (resume) a torn last row is dropped and reported — its point is computed
//! again; with [`Torn::Refuse`] (merge, whose inputs must be finished tables) it is refused. A bad
//! row anywhere else is corruption and always refused, naming the file and line.

use std::io::Read as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::folder::open_existing;
use crate::error::OutputError;

/// What to do with a torn last row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Torn {
    /// Drop it and say so ([`Table::dropped`]): a `.partial` file being resumed.
    DropLast,
    /// Refuse the file: a finished table.
    Refuse,
}

/// One row: its point, its line number (1-based), its bytes in the file and as raycost's CSV writer
/// writes them.
#[derive(Debug)]
pub struct Line {
    /// The point index in its first field.
    pub point: usize,
    /// 1-based line number.
    pub line: u64,
    /// Its bytes in the file (newline included).
    pub raw: Range<usize>,
    /// The record re-serialised by the runner's CSV settings (newline included).
    pub bytes: Vec<u8>,
}

/// A table read back and checked.
#[derive(Debug)]
pub struct Table {
    /// The file.
    pub path: PathBuf,
    /// The file's bytes (all of them, a dropped torn row included).
    pub text: Vec<u8>,
    /// The header line as the CSV writer writes it; `None` for an empty file.
    pub header: Option<Vec<u8>>,
    /// The header's bytes in the file (newline included).
    pub header_raw: Range<usize>,
    /// Column names.
    pub columns: Vec<String>,
    /// The valid rows, in file order.
    pub rows: Vec<Line>,
    /// With [`Torn::DropLast`]: what was dropped and why.
    pub dropped: Option<String>,
    /// Bytes of the file that are valid (everything before a dropped torn row).
    pub valid_len: usize,
}

fn err(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError::new(path, message)
}

fn record_bytes<'a>(fields: impl IntoIterator<Item = &'a [u8]>) -> Vec<u8> {
    let mut w = ::csv::Writer::from_writer(Vec::new());
    w.write_record(fields)
        .expect("writing to memory cannot fail");
    w.into_inner().expect("flush to memory")
}

/// 1-based line number of byte `at`.
fn line_of(text: &[u8], at: usize) -> u64 {
    text[..at].iter().filter(|&&b| b == b'\n').count() as u64 + 1
}

/// [`line_of`] for positions that only grow: counts the newlines since the last position asked
/// for, so reading a table row by row is linear in its size (counting from the start at every row
/// made a 41 MB points table take ten minutes).
struct Lines<'a> {
    text: &'a [u8],
    at: usize,
    line: u64,
}

impl<'a> Lines<'a> {
    fn new(text: &'a [u8]) -> Self {
        Lines {
            text,
            at: 0,
            line: 1,
        }
    }

    /// The 1-based line of byte `at` (never before the last one asked for).
    fn of(&mut self, at: usize) -> u64 {
        debug_assert!(at >= self.at);
        let newlines = self.text[self.at..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        self.line += newlines as u64;
        self.at = at;
        self.line
    }
}

/// Reads and checks `path` (a regular file, never read through a symlink: a `.partial` file about
/// to be appended to); `declared` are the column names its metadata records (`None`: not recorded,
/// as by partial runs of raycost before the partial metadata carried them).
pub fn read_table(
    path: &Path,
    declared: Option<&[String]>,
    torn: Torn,
) -> Result<Table, OutputError> {
    let mut text = Vec::new();
    open_existing(path, false)
        .and_then(|mut f| f.read_to_end(&mut text))
        .map_err(|e| err(path, format!("cannot read: {e}")))?;
    check_table(path, text, declared, torn)
}

/// The bytes of a finished table, gzip-decompressed if its name ends in `.gz` (as large committed
/// tables are kept): what `raycost reproduce` and `raycost crossover` read results from.
pub fn finished_table_bytes(path: &Path) -> Result<Vec<u8>, OutputError> {
    let raw = std::fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
    if path.extension().is_none_or(|e| e != "gz") {
        return Ok(raw);
    }
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(raw.as_slice())
        .read_to_end(&mut out)
        .map_err(|e| err(path, format!("is not a readable gzip file: {e}")))?;
    Ok(out)
}

/// The header and the rows of CSV text `text` (of table `path`, which errors name), as text cells.
pub fn text_cells(
    path: &Path,
    text: &[u8],
) -> Result<(Vec<String>, Vec<Vec<String>>), OutputError> {
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text);
    let bad = |e: ::csv::Error| err(path, format!("unreadable CSV: {e}"));
    let header = reader
        .headers()
        .map_err(bad)?
        .iter()
        .map(str::to_string)
        .collect();
    let rows = reader
        .records()
        .map(|r| r.map(|r| r.iter().map(str::to_string).collect()))
        .collect::<Result<Vec<Vec<String>>, _>>()
        .map_err(bad)?;
    Ok((header, rows))
}

/// Checks the bytes `text` of table `path` (see [`read_table`]).
pub fn check_table(
    path: &Path,
    text: Vec<u8>,
    declared: Option<&[String]>,
    torn: Torn,
) -> Result<Table, OutputError> {
    let mut t = Table {
        path: path.to_path_buf(),
        header: None,
        header_raw: 0..0,
        columns: Vec::new(),
        rows: Vec::new(),
        dropped: None,
        valid_len: text.len(),
        text,
    };
    let text = &t.text;
    let (mut end, mut why) = torn_tail(path, text)?;
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(&text[..end]);
    let mut record = ::csv::ByteRecord::new();
    let mut width = 0;
    let mut lines = Lines::new(text);
    // (line, start byte, problem) of the first bad row.
    let mut bad: Option<(u64, usize, String)> = None;
    loop {
        let start = reader.position().byte() as usize;
        match reader.read_byte_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                bad = Some((lines.of(start), start, format!("is unreadable CSV ({e})")));
                break;
            }
        }
        let line = lines.of(start);
        let stop = reader.position().byte() as usize;
        if let Some(f) = record.iter().find(|f| std::str::from_utf8(f).is_err()) {
            let f = String::from_utf8_lossy(f).into_owned();
            bad = Some((line, start, format!("is not UTF-8 text (field '{f}')")));
            break;
        }
        if t.header.is_none() {
            let columns = header_columns(path, line, &record, declared)?;
            width = record.len();
            t.header = Some(record_bytes(record.iter()));
            t.header_raw = start..stop;
            t.columns = columns;
            continue;
        }
        if record.len() != width {
            bad = Some((
                line,
                start,
                format!(
                    "has {} fields, but the header has {width} (a torn or corrupted row)",
                    record.len()
                ),
            ));
            break;
        }
        let cell = String::from_utf8_lossy(&record[0]).into_owned();
        let Ok(point) = cell.parse::<usize>() else {
            bad = Some((line, start, format!("point '{cell}' is not a point index")));
            break;
        };
        t.rows.push(Line {
            point,
            line,
            raw: start..stop,
            bytes: record_bytes(record.iter()),
        });
    }
    if let Some((line, start, what)) = bad {
        // Only the very last line may be torn, and only one line may be.
        let last = reader.position().byte() as usize >= end;
        if torn == Torn::Refuse || !last || why.is_some() {
            return Err(err(path, format!("line {line} {what}")));
        }
        why = Some((line, what));
        end = start;
    }
    if let Some((line, what)) = why {
        if torn == Torn::Refuse {
            return Err(err(path, format!("line {line} {what}")));
        }
        t.dropped = Some(format!(
            "{}: line {line} {what}; dropped it ({} bytes), its point is computed again",
            path.display(),
            t.text.len() - end
        ));
        t.valid_len = end;
    }
    Ok(t)
}

/// Where a table's intact text ends: before zeros a crash left, or bytes after the last
/// newline; with the line and reason of what is cut. NUL bytes followed by data are refused.
fn torn_tail(path: &Path, text: &[u8]) -> Result<(usize, Option<(u64, String)>), OutputError> {
    let mut end = text.len();
    let mut why: Option<(u64, String)> = None;
    if let Some(z) = text.iter().position(|&b| b == 0) {
        let start = text[..z]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        if text[z..].iter().any(|&b| b != 0) {
            return Err(err(
                path,
                format!(
                    "line {} holds NUL bytes followed by more data: the file is corrupted",
                    line_of(text, z)
                ),
            ));
        }
        end = start;
        why = Some((
            line_of(text, z),
            "ends in NUL bytes (a crash zero-filled its last block)".into(),
        ));
    }
    if end > 0 && text[end - 1] != b'\n' {
        let start = text[..end]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        why = why.or(Some((
            line_of(text, start),
            "is truncated (the file does not end with a newline: the last write was cut short)"
                .into(),
        )));
        end = start;
    }
    Ok((end, why))
}

/// The header's column names: `point` first, and the declared columns where the metadata
/// records them.
fn header_columns(
    path: &Path,
    line: u64,
    record: &::csv::ByteRecord,
    declared: Option<&[String]>,
) -> Result<Vec<String>, OutputError> {
    let columns: Vec<String> = record
        .iter()
        .map(|f| String::from_utf8_lossy(f).into_owned())
        .collect();
    if columns.first().map(String::as_str) != Some("point") {
        return Err(err(
            path,
            format!(
                "line {line}: the first column is '{}', expected 'point' (not a raycost table)",
                columns.first().map_or("", String::as_str)
            ),
        ));
    }
    if let Some(d) = declared.filter(|d| !d.is_empty()) {
        check_declared(path, &columns, d)?;
    }
    Ok(columns)
}

/// The header must be the columns the metadata records for this table.
fn check_declared(path: &Path, columns: &[String], declared: &[String]) -> Result<(), OutputError> {
    if columns == declared {
        return Ok(());
    }
    let i = columns
        .iter()
        .zip(declared)
        .position(|(a, b)| a != b)
        .unwrap_or(columns.len().min(declared.len()));
    let col = |c: &[String]| {
        c.get(i)
            .map_or_else(|| "(none)".to_string(), |s| format!("'{s}'"))
    };
    Err(err(
        path,
        format!(
            "its header is not the columns its metadata records: column {} is {} here, {} there \
             ({} vs {} columns): the table and its metadata come from different runs",
            i + 1,
            col(columns),
            col(declared),
            columns.len(),
            declared.len()
        ),
    ))
}

impl Table {
    /// The valid bytes of the file, keeping only the rows `keep` accepts: the header and those rows
    /// as they are in the file.
    pub fn kept(&self, keep: impl Fn(&Line) -> bool) -> Vec<u8> {
        let mut out = self.text[self.header_raw.clone()].to_vec();
        for r in self.rows.iter().filter(|r| keep(r)) {
            out.extend_from_slice(&self.text[r.raw.clone()]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "point,a,b\n0,1.5,x\n1,2.5,\"y,z\"\n";

    fn read(text: &[u8], torn: Torn) -> Result<Table, OutputError> {
        let d = tempfile::tempdir().expect("tempdir");
        let p = d.path().join("t.csv");
        std::fs::write(&p, text).expect("write");
        read_table(&p, None, torn)
    }

    #[test]
    fn a_good_table_reads_back_whole() {
        let t = read(GOOD.as_bytes(), Torn::Refuse).expect("good");
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.kept(|_| true), GOOD.as_bytes());
        assert!(t.dropped.is_none());
    }

    /// Every way to tear the last row is dropped on resume and refused on merge; the same damage
    /// one row earlier is refused on both.
    #[test]
    fn torn_last_rows_are_dropped_torn_middle_rows_refused() {
        let tears: Vec<Vec<u8>> = vec![
            format!("{GOOD}2,3.").into_bytes(),          // cut mid-field
            format!("{GOOD}2,3.5\n").into_bytes(),       // cut at a field, newline kept
            format!("{GOOD}2,3.5,w\0\0\0").into_bytes(), // zero-filled tail
            [GOOD.as_bytes(), &[0u8; 64]].concat(),      // zeros only
            format!("{GOOD}2,3.5,\"w").into_bytes(),     // inside a quoted field
            format!("{GOOD}x,3.5,w\n").into_bytes(),     // a garbled point
        ];
        for t in &tears {
            let r = read(t, Torn::DropLast).expect("dropped on resume");
            assert_eq!(r.rows.len(), 2, "{:?}", String::from_utf8_lossy(t));
            assert!(
                r.dropped.as_deref().is_some_and(|d| d.contains("line")),
                "{r:?}"
            );
            assert_eq!(&r.text[..r.valid_len], GOOD.as_bytes());
            assert!(read(t, Torn::Refuse).is_err());
        }
        for middle in [
            "point,a,b\n0,1.5\n1,2.5,y\n",
            "point,a,b\n0,1.5,x\0\n1,2.5,y\n",
            "point,a,b\n0,1.5,x\nx,2.5,y\n2,3.5,z\n",
        ] {
            assert!(
                read(middle.as_bytes(), Torn::DropLast).is_err(),
                "{middle:?}"
            );
        }
        // Two torn rows (the last cut, the one before short) are not one torn write: refused.
        assert!(read(b"point,a,b\n0,1.5,x\n1,2.5\n2,3.", Torn::DropLast).is_err());
    }

    #[test]
    fn headers_are_checked_against_the_declared_columns() {
        let d = tempfile::tempdir().expect("tempdir");
        let p = d.path().join("t.csv");
        std::fs::write(&p, GOOD).expect("write");
        let want = |c: &[&str]| c.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(read_table(&p, Some(&want(&["point", "a", "b"])), Torn::Refuse).is_ok());
        let e = read_table(&p, Some(&want(&["point", "a", "c"])), Torn::DropLast)
            .expect_err("another run's table");
        assert!(e.message.contains("column 3"), "{e}");
        // A truncated header is a torn last line: nothing is left but an empty table.
        let t = read(b"point,a", Torn::DropLast).expect("torn header");
        assert!(t.header.is_none() && t.valid_len == 0);
        assert!(read(b"x,a,b\n0,1,2\n", Torn::DropLast).is_err());
    }
}
