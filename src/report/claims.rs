//! `RESULTS/claims.toml`: the papers' claims and what raycost measured for each, written by hand
//! and checked when the report is made (format in docs/report.md).
//!
//! ```toml
//! [[claim]]
//! claim = "E[N_S] = 1.5·E[t*]/a for an eye uniform in its cell"
//! reference = "Márton & Szirmay-Kalos 2022, Result 3.1"   # optional
//! paper = 190.99                       # the paper's number (or text, e.g. "≈ 0.35")
//! source = "grid-first-hit/grid-first-hit.csv"            # relative to RESULTS; must exist
//! column = "n_s"                       # read M_mean, M_se, M_n (or the value M) from source …
//! point = 0                            # … in the row whose `point` is this
//! # or, instead of column/point: measured = 190.6, ci = 0.58 (95 % half-width),
//! # or a text that states its own uncertainty: measured = "40 of 40 points inside"
//! headline = "crossing 0.163 [0.129, 0.210]"   # optional: the one number to hold against `paper`
//! units = ["lines: crossing 0.163 [0.129, 0.210] (undecided: …)"]  # optional: every judged unit
//! unit = "steps"                       # optional
//! verdict = "ok (99% CI)"              # optional with `column` and a numeric `paper`
//! outcome = "holds"                    # optional: holds, holds-in-part, differs, refuted, inconclusive
//! rule = "theorem-2/2"                 # optional: the pre-registered rule that decided it
//! accounting = "paper"                 # optional: the cost model it was judged in
//! earlier = "…"                        # optional: what earlier rules gave
//! note = "…"                           # optional
//! ```
//!
//! With `column`, the measured value and its CI come from the table itself (they cannot drift from
//! it), and without a `verdict` the claim is judged against the paper's number by the summary's own
//! rule ([`z_verdict`]). A claim is coloured by its `outcome`, or without one by its verdict read as
//! an outcome or a verdict ([`claim_tone`]). Every problem is an [`InputError`] naming the file,
//! line and key.

use std::path::Path;

use serde::Deserialize;

use crate::error::InputError;
use crate::output::column::{part, POINT};
use crate::output::summary::measured;
use crate::stats::verdict::z_verdict;
use crate::stats::Estimate;
use crate::toml_text::de::from_text;

use super::table::{display, Table};
use super::verdicts::{claim_tone, Outcome, Tone};

/// The file name looked for in RESULTS.
pub const FILE: &str = "claims.toml";

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimsFile {
    /// The claims engine's version that judged them (`claims/engine-versions.toml`); the page
    /// shows the verdicts as judged, whatever the version.
    #[serde(default, rename = "engine")]
    _engine: Option<u64>,
    #[serde(default)]
    claim: Vec<Entry>,
}

/// A number or a text.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
enum NumberOrText {
    Number(f64),
    Text(String),
}

/// One `[[claim]]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    claim: String,
    #[serde(default)]
    reference: Option<String>,
    paper: NumberOrText,
    source: String,
    #[serde(default)]
    column: Option<String>,
    #[serde(default)]
    point: Option<u64>,
    #[serde(default)]
    measured: Option<NumberOrText>,
    #[serde(default)]
    headline: Option<String>,
    #[serde(default)]
    units: Vec<String>,
    #[serde(default)]
    ci: Option<f64>,
    #[serde(default)]
    unit: Option<String>,
    #[serde(default)]
    verdict: Option<String>,
    #[serde(default)]
    outcome: Option<String>,
    #[serde(default)]
    rule: Option<String>,
    #[serde(default)]
    accounting: Option<String>,
    #[serde(default)]
    earlier: Option<String>,
    #[serde(default)]
    note: Option<String>,
}

/// The outcomes a claim can have (`outcome` in the file; scripts/claims_rules.py writes them):
/// the spellings of [`Outcome`].
pub const OUTCOMES: [&str; 5] = [
    Outcome::ALL[0].0,
    Outcome::ALL[1].0,
    Outcome::ALL[2].0,
    Outcome::ALL[3].0,
    Outcome::ALL[4].0,
];

/// One claim, resolved, as the page shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperClaim {
    /// What the paper claims.
    pub claim: String,
    /// Where it says so.
    pub reference: String,
    /// The paper's number, as given.
    pub paper: String,
    /// The one measured number (or interval) a reader holds against the paper's, with its unit
    /// count (empty if not given); `units` holds every unit.
    pub headline: String,
    /// Every judged unit, one text each (empty if not given): `measured` lists the first few.
    pub units: Vec<String>,
    /// Measured ± 95 % CI (with the unit, if given).
    pub measured: String,
    /// The verdict.
    pub verdict: String,
    /// Its tone.
    pub tone: Tone,
    /// The typed outcome (one of [`OUTCOMES`]) when the file gives one; the page colours by it.
    pub outcome: Option<String>,
    /// The pre-registered rule that decided it (empty if not given).
    pub rule: String,
    /// The accounting it was judged in (empty if not given).
    pub accounting: String,
    /// What earlier rules gave (empty if not given).
    pub earlier: String,
    /// The source CSV, relative to RESULTS, as written.
    pub source: String,
    /// The source CSV for the page's link: absolute when loaded, made relative to DIR by
    /// [`super::assemble`].
    pub link: std::path::PathBuf,
    /// The note.
    pub note: String,
}

/// Reads `RESULTS/claims.toml` if it exists (`Ok(None)` if not).
pub fn load(results: &Path) -> Result<Option<Vec<PaperClaim>>, InputError> {
    let path = results.join(FILE);
    if !path.exists() {
        return Ok(None);
    }
    let file = path.display().to_string();
    let text = std::fs::read_to_string(&path)
        .map_err(|e| InputError::new(&file, format!("cannot read the claims: {e}")))?;
    parse(&text, results).map(Some).map_err(|(e, key, at)| {
        let mut err = InputError::new(&file, e).at(at);
        if let Some(k) = key {
            err = err.key(k);
        }
        err
    })
}

/// An error before it is given its file: message, key, line and column.
type Located = (String, Option<String>, Option<(usize, usize)>);

/// Parses claims text; `source` paths are resolved against `results`.
fn parse(text: &str, results: &Path) -> Result<Vec<PaperClaim>, Located> {
    let f: ClaimsFile = from_text(text).map_err(|e| (e.message, e.key, e.at))?;
    f.claim
        .into_iter()
        .enumerate()
        .map(|(i, e)| {
            resolve(e, results).map_err(|(key, msg)| {
                let key = format!("claim[{i}].{key}");
                // The entry's `[[claim]]` header (best effort: serde has no span here).
                let at = text
                    .match_indices("[[claim]]")
                    .nth(i)
                    .map(|(o, _)| crate::toml_text::line_col(text, o));
                (msg, Some(key), at)
            })
        })
        .collect()
}

/// Checks one entry and fills in what comes from its table; an error names the key at fault.
fn resolve(e: Entry, results: &Path) -> Result<PaperClaim, (&'static str, String)> {
    let path = results.join(&e.source);
    if !path.is_file() {
        return Err((
            "source",
            format!(
                "{} is not a file (give a CSV path relative to {})",
                e.source,
                results.display()
            ),
        ));
    }
    let paper_number = match &e.paper {
        NumberOrText::Number(x) => Some(*x),
        NumberOrText::Text(_) => None,
    };
    let paper = match &e.paper {
        NumberOrText::Number(x) => x.to_string(),
        NumberOrText::Text(s) => s.clone(),
    };
    let unit = e.unit.as_deref().map_or(String::new(), |u| format!(" {u}"));
    let (measured_text, est) = match (&e.column, e.measured.clone()) {
        (Some(_), Some(_)) => {
            return Err((
                "measured",
                "give either `column` (read from the source table) or `measured`, not both".into(),
            ))
        }
        (None, None) => return Err((
            "measured",
            "missing: give `column` (and `point`) to read it from the source table, or `measured`"
                .into(),
        )),
        (None, Some(NumberOrText::Text(t))) => {
            if e.point.is_some() || e.ci.is_some() {
                return Err((
                    "measured",
                    "a measurement given as text carries its own uncertainty: no `point` or `ci`"
                        .into(),
                ));
            }
            (format!("{t}{unit}"), None)
        }
        (None, Some(NumberOrText::Number(m))) => {
            if e.point.is_some() {
                return Err(("point", "`point` needs `column`".into()));
            }
            let text = match e.ci {
                Some(c) if c.is_finite() && c >= 0.0 => format!("{m} ± {c}{unit}"),
                Some(c) => return Err(("ci", format!("got {c}, expected a number ≥ 0"))),
                None => format!("{m}{unit}"),
            };
            (text, None)
        }
        (Some(col), None) => {
            if e.ci.is_some() {
                return Err((
                    "ci",
                    "comes from the source table with `column`; remove it".into(),
                ));
            }
            let t = Table::read(&path).map_err(|err| ("source", err.to_string()))?;
            let (est, text) = from_table(&t, col, e.point)?;
            (format!("{text}{unit}"), Some(est))
        }
    };
    let verdict = match (e.verdict, est, paper_number) {
        (Some(v), _, _) => v,
        (None, Some(est), Some(p)) => z_verdict(&est, p).to_string(),
        (None, _, _) => {
            return Err((
                "verdict",
                "missing (it is computed only with `column` and a numeric `paper`)".into(),
            ))
        }
    };
    // The typed outcome, read by the enum the page's colours come from.
    let outcome: Option<Outcome> = match &e.outcome {
        Some(o) => Some(o.parse().map_err(|m| ("outcome", m))?),
        None => None,
    };
    Ok(PaperClaim {
        claim: e.claim,
        reference: e.reference.unwrap_or_default(),
        paper,
        headline: e.headline.unwrap_or_default(),
        units: e.units,
        measured: measured_text,
        tone: claim_tone(outcome, &verdict),
        verdict,
        outcome: e.outcome,
        rule: e.rule.unwrap_or_default(),
        accounting: e.accounting.unwrap_or_default(),
        earlier: e.earlier.unwrap_or_default(),
        source: e.source,
        link: path.canonicalize().unwrap_or(path),
        note: e.note.unwrap_or_default(),
    })
}

/// The estimate of column stem `col` in the row whose `point` cell is `point` (the only row when
/// `point` is not given), and its text: measured ± CI as the summary prints it, or a plain
/// column's value as the table holds it.
fn from_table(
    t: &Table,
    col: &str,
    point: Option<u64>,
) -> Result<(Estimate, String), (&'static str, String)> {
    let row = match point {
        Some(p) => (0..t.rows.len())
            .find(|&r| t.cell(r, POINT.name) == Some(p.to_string().as_str()))
            .ok_or((
                "point",
                format!("no row with point = {p} in the source table"),
            ))?,
        None if t.rows.len() == 1 => 0,
        None => {
            return Err((
                "point",
                format!("missing: the source table has {} rows", t.rows.len()),
            ))
        }
    };
    if t.has(&part::name(col, part::MEAN)) {
        let est = super::verdicts::estimate(t, row, col);
        Ok((est, measured(&est)))
    } else if t.has(col) {
        // One value, no standard error: judged as an exact value (SE 0; the cluster count does
        // not enter a verdict with SE 0).
        let est = Estimate {
            mean: t.number(row, col),
            se: 0.0,
            n: 1,
            clusters: 1,
        };
        Ok((est, display(t.cell(row, col).unwrap_or(""))))
    } else {
        Err((
            "column",
            format!(
                "the source table has neither {} nor {col}",
                part::name(col, part::MEAN)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn results() -> tempfile::TempDir {
        let d = tempfile::tempdir().expect("tempdir");
        std::fs::create_dir(d.path().join("a")).expect("mkdir");
        std::fs::write(
            d.path().join("a/a.csv"),
            "point,n_s_mean,n_s_se,n_s_n,count\n0,190.6,0.3,400000,7\n1,21.0,0.03,400000,8\n",
        )
        .expect("write");
        d
    }

    #[test]
    fn a_column_claim_reads_its_table_and_is_judged() {
        let d = results();
        let text = r#"
[[claim]]
claim = "E[N_S]"
paper = 190.98
source = "a/a.csv"
column = "n_s"
point = 0
unit = "steps"

[[claim]]
claim = "crossover"
reference = "Theorem 2"
paper = "≈ 0.35"
source = "a/a.csv"
measured = 0.36
ci = 0.02
verdict = "agrees"
"#;
        let c = parse(text, d.path()).expect("claims");
        assert_eq!(c.len(), 2);
        assert!(
            c[0].measured.starts_with("190.6000 ± 0.58"),
            "{}",
            c[0].measured
        );
        assert!(c[0].measured.ends_with(" steps"));
        assert_eq!(c[0].verdict, "ok (99% CI)");
        assert_eq!(c[0].paper, "190.98");
        assert_eq!(c[1].measured, "0.36 ± 0.02");
        assert_eq!(
            (c[1].paper.as_str(), c[1].verdict.as_str()),
            ("≈ 0.35", "agrees")
        );
        // A measurement given as text is shown as written; it carries no separate `ci`.
        let t = "[[claim]]\nclaim = \"x\"\npaper = \"0.35\"\nsource = \"a/a.csv\"\nmeasured = \"0.12 [0.10, 0.15]\"\nverdict = \"differs\"\n";
        let c = parse(t, d.path()).expect("text");
        assert_eq!(c[0].measured, "0.12 [0.10, 0.15]");
        let e = parse(&format!("{t}ci = 0.1\n"), d.path()).expect_err("ci with text");
        // The headline and every unit, as claims.py writes them beside `measured`.
        let c = parse(
            &format!("{t}headline = \"crossing 0.12\"\nunits = [\"a: 1\", \"b: 2\"]\n"),
            d.path(),
        )
        .expect("headline and units");
        assert_eq!(c[0].headline, "crossing 0.12");
        assert_eq!(c[0].units, ["a: 1", "b: 2"]);
        assert!(parse(t, d.path()).expect("without")[0].units.is_empty());
        assert_eq!(e.1.as_deref(), Some("claim[0].measured"));
    }

    #[test]
    fn problems_are_named_by_key() {
        let d = results();
        let err = |t: &str| parse(t, d.path()).expect_err("refused");
        let base = "[[claim]]\nclaim = \"x\"\npaper = 1.0\n";
        let e = err(&format!("{base}source = \"nope.csv\"\nmeasured = 1.0\n"));
        assert_eq!(e.1.as_deref(), Some("claim[0].source"));
        let e = err(&format!("{base}source = \"a/a.csv\"\ncolumn = \"n_s\"\n"));
        assert!(e.0.contains("2 rows"), "{}", e.0);
        let e = err(&format!(
            "{base}source = \"a/a.csv\"\ncolumn = \"zz\"\npoint = 1\n"
        ));
        assert_eq!(e.1.as_deref(), Some("claim[0].column"));
        let e = err(&format!("{base}source = \"a/a.csv\"\nmeasured = 1.0\n"));
        assert_eq!(e.1.as_deref(), Some("claim[0].verdict"));
        let e = err(&format!(
            "{base}source = \"a/a.csv\"\nmeasured = 1.0\nverdict = \"x\"\noutcome = \"fine\"\n"
        ));
        assert_eq!(e.1.as_deref(), Some("claim[0].outcome"));
        assert!(e.0.contains("holds-in-part"), "{}", e.0);
        let c = parse(
            &format!("{base}source = \"a/a.csv\"\nmeasured = 1.0\nverdict = \"holds: 1 of 1\"\noutcome = \"holds\"\nrule = \"r/2\"\naccounting = \"paper\"\n"),
            d.path(),
        )
        .expect("outcome");
        assert_eq!(
            (
                c[0].outcome.as_deref(),
                c[0].rule.as_str(),
                c[0].accounting.as_str()
            ),
            (Some("holds"), "r/2", "paper")
        );
        let e = err(&format!(
            "{base}source = \"a/a.csv\"\nmeasured = 1.0\ncolour = 1\n"
        ));
        assert!(e.0.contains("unknown field"), "{}", e.0);
        assert!(e.2.is_some(), "serde errors carry line and column");
        // An exact value read from a plain column: judged with SE 0.
        let c = parse(
            &format!("{base}source = \"a/a.csv\"\ncolumn = \"count\"\npoint = 1\n")
                .replace("paper = 1.0", "paper = 8"),
            d.path(),
        )
        .expect("plain column");
        assert_eq!(
            (c[0].measured.as_str(), c[0].verdict.as_str()),
            ("8", "ok (exact)")
        );
    }

    #[test]
    fn no_file_is_no_claims() {
        let d = results();
        assert_eq!(load(d.path()).expect("none"), None);
    }
}
