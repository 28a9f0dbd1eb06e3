//! The verdict of a measurement against theory, as one typed value: the terminal summary, the `_band`
//! column of a table, `raycost report` and the claims table all take it from here, and read a
//! verdict cell back with [`Verdict::from_str`](std::str::FromStr), which accepts exactly what
//! [`Verdict`]'s `Display` writes (never a prefix). Each verdict has a [`Tone`]: whether the
//! measurement agrees with the theory, disagrees, could not be judged for want of an error bar
//! (inconclusive), or was deliberately not judged (a law that does not apply, a single value against
//! a model, a speed-up).
//!
//! The rules: against a prediction, "ok" when the prediction lies within the measurement's 99 % CI
//! (Student-t on clusters − 1 degrees of freedom, [`Estimate::half_width`]), else the distance in
//! standard errors; against a band, where the 95 % CI falls (`below`, `inside`, `above`); `n/a`
//! without a standard error or a finite theory.

use std::fmt;
use std::str::FromStr;

use super::Estimate;

/// What a metric is held against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Theory {
    /// A prediction: the verdict is "ok" within the 99 % CI, else the distance in SE.
    Prediction(f64),
    /// A prediction and a band `[lower, upper]`: the verdict says where the 95 % CI falls.
    Band {
        /// The prediction.
        prediction: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
}

impl Theory {
    /// The verdict of `est` against this theory: [`z_verdict`] for a prediction, [`band_verdict`]
    /// for a band.
    pub fn verdict(&self, est: &Estimate) -> Verdict {
        match *self {
            Theory::Prediction(p) => z_verdict(est, p),
            Theory::Band { lower, upper, .. } => band_verdict(est, lower, upper),
        }
    }

    /// The theory as the summary prints it: `prediction` or `prediction [lower, upper]`.
    pub fn describe(&self) -> String {
        match *self {
            Theory::Prediction(p) => format!("{p:.4}"),
            Theory::Band {
                prediction,
                lower,
                upper,
            } => format!("{prediction:.3} [{lower:.3}, {upper:.3}]"),
        }
    }
}

/// What a verdict means, for colour and for counting.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Tone {
    /// The measurement agrees with the theory (`ok …`, `inside`).
    Agrees,
    /// It does not (`±k SE`, `below`, `above`, `differs (SE 0)`, a failed check).
    Disagrees,
    /// Nothing can be said: no standard error, or no finite theory (`n/a`).
    Inconclusive,
    /// Deliberately not judged: a law that does not apply, one value against a model, a speed-up.
    NotJudged,
}

impl Tone {
    /// The spelling in pages and metadata.
    pub fn as_str(self) -> &'static str {
        match self {
            Tone::Agrees => "agrees",
            Tone::Disagrees => "disagrees",
            Tone::Inconclusive => "inconclusive",
            Tone::NotJudged => "not-judged",
        }
    }
}

/// A verdict (see the module doc); `Display` gives the text every table and page shows.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// `ok (99% CI)`: the prediction lies within the measurement's 99 % CI.
    Agrees,
    /// `ok (exact)`: an exact value (SE 0) equal to the prediction; also a check with no failure.
    Exact,
    /// `+3.0 SE`: the prediction lies outside the 99 % CI, this many standard errors away
    /// ((measured − theory)/SE; printed with one decimal).
    Off(f64),
    /// `differs (SE 0)`: an exact value (SE 0) that differs from the prediction.
    DiffersExactly,
    /// `inside`: the 95 % CI meets the band.
    Inside,
    /// `below`: the 95 % CI lies below the band.
    Below,
    /// `above`: the 95 % CI lies above the band.
    Above,
    /// `n/a`: no standard error (one cluster) or no finite theory.
    NotAvailable,
    /// `×1.20 (photons: not judged)`: shown against a law that does not apply here (`why`), with
    /// the ratio measured/law where both are finite and the law is not 0.
    NotJudged {
        /// measured / law.
        ratio: Option<f64>,
        /// Why the law does not apply.
        why: String,
    },
    /// `no verdict (one value; measured/theory = 1.250)`: a single value (no standard error)
    /// against a model.
    OneValue(f64),
    /// `FAIL`: a built-in check found failures.
    Fail,
    /// `4.0× faster`: a speed-up, shown, not judged.
    Faster(f64),
}

impl Verdict {
    /// What it means.
    pub fn tone(&self) -> Tone {
        match self {
            Verdict::Agrees | Verdict::Exact | Verdict::Inside => Tone::Agrees,
            Verdict::Off(_)
            | Verdict::DiffersExactly
            | Verdict::Below
            | Verdict::Above
            | Verdict::Fail => Tone::Disagrees,
            Verdict::NotAvailable => Tone::Inconclusive,
            Verdict::NotJudged { .. } | Verdict::OneValue(_) | Verdict::Faster(_) => {
                Tone::NotJudged
            }
        }
    }

    /// The verdict of a built-in check: `ok (exact)` with no failure, else `FAIL`.
    pub fn of_check(failures: u64) -> Verdict {
        if failures == 0 {
            Verdict::Exact
        } else {
            Verdict::Fail
        }
    }
}

impl fmt::Display for Verdict {
    /// The text, padded as the formatter asks (the summary aligns its verdict column).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Verdict::Agrees => "ok (99% CI)".to_string(),
            Verdict::Exact => "ok (exact)".to_string(),
            Verdict::Off(z) => format!("{z:+.1} SE"),
            Verdict::DiffersExactly => "differs (SE 0)".to_string(),
            Verdict::Inside => "inside".to_string(),
            Verdict::Below => "below".to_string(),
            Verdict::Above => "above".to_string(),
            Verdict::NotAvailable => "n/a".to_string(),
            Verdict::NotJudged {
                ratio: Some(r),
                why,
            } => format!("×{r:.2} ({why}: not judged)"),
            Verdict::NotJudged { ratio: None, why } => format!("({why}: not judged)"),
            Verdict::OneValue(r) => format!("no verdict (one value; measured/theory = {r:.3})"),
            Verdict::Fail => "FAIL".to_string(),
            Verdict::Faster(x) => format!("{x:.1}× faster"),
        };
        f.pad(&text)
    }
}

/// A text that is not a verdict.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NotAVerdict(pub String);

impl fmt::Display for NotAVerdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "\"{}\" is not a verdict", self.0)
    }
}

impl std::error::Error for NotAVerdict {}

impl FromStr for Verdict {
    type Err = NotAVerdict;

    /// Exactly the texts `Display` writes (numbers as written), nothing else.
    fn from_str(s: &str) -> Result<Verdict, NotAVerdict> {
        let bad = || NotAVerdict(s.to_string());
        let number = |t: &str| t.parse::<f64>().ok().filter(|x| x.is_finite());
        Ok(match s {
            "ok (99% CI)" => Verdict::Agrees,
            "ok (exact)" => Verdict::Exact,
            "differs (SE 0)" => Verdict::DiffersExactly,
            "inside" => Verdict::Inside,
            "below" => Verdict::Below,
            "above" => Verdict::Above,
            "n/a" => Verdict::NotAvailable,
            "FAIL" => Verdict::Fail,
            _ => {
                if let Some(z) = s.strip_suffix(" SE") {
                    let signed = z.starts_with('+') || z.starts_with('-');
                    Verdict::Off(number(z).filter(|_| signed).ok_or_else(bad)?)
                } else if let Some(r) = s.strip_suffix("× faster") {
                    Verdict::Faster(number(r).ok_or_else(bad)?)
                } else if let Some(r) = s
                    .strip_prefix("no verdict (one value; measured/theory = ")
                    .and_then(|r| r.strip_suffix(')'))
                {
                    Verdict::OneValue(number(r).ok_or_else(bad)?)
                } else if let Some(inner) = s.strip_suffix(": not judged)") {
                    let (ratio, why) = match inner.split_once(" (") {
                        Some((r, why)) => {
                            let r = r.strip_prefix('×').and_then(number).ok_or_else(bad)?;
                            (Some(r), why)
                        }
                        None => (None, inner.strip_prefix('(').ok_or_else(bad)?),
                    };
                    if why.is_empty() {
                        return Err(bad());
                    }
                    Verdict::NotJudged {
                        ratio,
                        why: why.to_string(),
                    }
                } else {
                    return Err(bad());
                }
            }
        })
    }
}

/// Where a measured mean falls against a band `[lower, upper]`, judged by its 95 % CI: `below`,
/// `inside` or `above`; `n/a` when the estimate has no standard error (a single cluster), because
/// then nothing can be said about where the true mean lies.
pub fn band_verdict(e: &Estimate, lower: f64, upper: f64) -> Verdict {
    let h = e.half_width(0.95);
    if !h.is_finite() || !e.mean.is_finite() {
        Verdict::NotAvailable
    } else if e.mean + h < lower {
        Verdict::Below
    } else if e.mean - h > upper {
        Verdict::Above
    } else {
        Verdict::Inside
    }
}

/// The verdict against a law the experiment documents as not applying (`why`: e.g. photons of a
/// scene against the uniform-line law): the ratio measured/law, marked as not judged, never a
/// distance in SE.
pub fn not_judged(e: &Estimate, law: f64, why: &str) -> Verdict {
    let ratio = (e.mean.is_finite() && law.is_finite() && law != 0.0).then(|| e.mean / law);
    Verdict::NotJudged {
        ratio,
        why: why.to_string(),
    }
}

/// "ok" when the measurement is within its 99 % CI (Student-t, clusters − 1 dof) of a prediction,
/// else how many SE away; `n/a` without a standard error or a finite prediction.
pub fn z_verdict(e: &Estimate, theory: f64) -> Verdict {
    if !theory.is_finite() || !e.mean.is_finite() {
        return Verdict::NotAvailable;
    }
    if e.se == 0.0 {
        return if e.mean == theory {
            Verdict::Exact
        } else {
            Verdict::DiffersExactly
        };
    }
    let h = e.half_width(0.99);
    if !h.is_finite() {
        return Verdict::NotAvailable;
    }
    if (e.mean - theory).abs() <= h {
        Verdict::Agrees
    } else {
        Verdict::Off((e.mean - theory) / e.se)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn est(mean: f64, se: f64, clusters: u64) -> Estimate {
        Estimate {
            mean,
            se,
            n: 1000,
            clusters,
        }
    }

    #[test]
    fn band_verdicts_use_the_confidence_interval_and_refuse_without_one() {
        assert_eq!(
            band_verdict(&est(5.0, 0.1, 100), 1.0, 10.0),
            Verdict::Inside
        );
        // The CI reaches 10.
        assert_eq!(
            band_verdict(&est(10.1, 0.1, 100), 1.0, 10.0),
            Verdict::Inside
        );
        assert_eq!(
            band_verdict(&est(11.0, 0.1, 100), 1.0, 10.0),
            Verdict::Above
        );
        assert_eq!(band_verdict(&est(0.5, 0.1, 100), 1.0, 10.0), Verdict::Below);
        assert_eq!(
            band_verdict(&est(4.5, f64::NAN, 1), 1.0, 2.7),
            Verdict::NotAvailable
        );
    }

    #[test]
    fn a_law_that_does_not_apply_gives_a_ratio_not_a_verdict() {
        let v = not_judged(&est(120.0, 0.1, 100), 100.0, "photons");
        assert_eq!(v.to_string(), "×1.20 (photons: not judged)");
        assert_eq!(v.tone(), Tone::NotJudged);
        assert_eq!(
            not_judged(&est(1.0, 0.1, 100), 0.0, "photons").to_string(),
            "(photons: not judged)"
        );
    }

    #[test]
    fn z_verdicts_widen_with_few_clusters() {
        // 3 SE away: outside a 99 % normal CI, inside the t₃ one (5.84 SE).
        assert_eq!(z_verdict(&est(3.0, 1.0, 1000), 0.0).to_string(), "+3.0 SE");
        assert_eq!(z_verdict(&est(3.0, 1.0, 4), 0.0), Verdict::Agrees);
        assert_eq!(z_verdict(&est(1.0, 0.0, 10), 1.0), Verdict::Exact);
        assert_eq!(
            z_verdict(&est(1.0, f64::NAN, 1), 1.0),
            Verdict::NotAvailable
        );
    }

    /// Every verdict reads back from its own text, with its tone, and nothing else reads as one:
    /// a cell is classed by the whole text, never by a prefix.
    #[test]
    fn every_verdict_reads_back_and_nothing_else_does() {
        let all = [
            Verdict::Agrees,
            Verdict::Exact,
            Verdict::Off(3.04),
            Verdict::Off(-7.3),
            Verdict::DiffersExactly,
            Verdict::Inside,
            Verdict::Below,
            Verdict::Above,
            Verdict::NotAvailable,
            not_judged(&est(120.0, 0.1, 100), 100.0, "photons"),
            not_judged(&est(1.0, 0.1, 100), 0.0, "photons"),
            Verdict::OneValue(1.25),
            Verdict::Fail,
            Verdict::Faster(7.04),
        ];
        for v in &all {
            let text = v.to_string();
            let back: Verdict = text.parse().unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(back.to_string(), text);
            assert_eq!(back.tone(), v.tone(), "{text}");
        }
        for bad in [
            "ok",
            "okay (99% CI)",
            "inside the band",
            "3.0 SE",
            "+x SE",
            "holds",
            "",
            "() not judged)",
            "n/a (the run: inside)",
        ] {
            assert!(bad.parse::<Verdict>().is_err(), "{bad:?} read as a verdict");
        }
        assert_eq!(format!("{:<8}|", Verdict::Inside), "inside  |");
    }
}
