//! The HTML of the report: a [`Report`] in, one page out. Plain HTML5 and an inline style sheet, no
//! script and nothing fetched from the network (the icon is an empty `data:` URL, so a browser does
//! not ask for `/favicon.ico`). Every string from the results goes through [`html::text`] or
//! [`html::href`]; the markup here is the only unescaped text.

use std::fmt::Write as _;

use super::claims::PaperClaim;
use super::html::{anchor, href, text};
use super::meta_view::MetaView;
use super::verdicts::{PointClaims, Tone};
use super::{BenchSection, ExperimentSection, Files, OtherSection, Report};

/// The style sheet: readable type, tables with rules, verdicts coloured by tone.
const CSS: &str = "
body { font: 15px/1.45 system-ui, -apple-system, 'Segoe UI', sans-serif; color: #1b1b1b;
       max-width: 1180px; margin: 0 auto; padding: 0 1.2em 4em; }
h1 { margin-top: 1em; } h2 { border-bottom: 2px solid #ddd; padding-bottom: .2em; margin-top: 2.2em; }
td.name { white-space: nowrap; }
code, .mono, td.name { font-family: ui-monospace, 'DejaVu Sans Mono', monospace; font-size: 90%; }
nav ul { columns: 3; padding-left: 1.2em; }
dl.meta { display: grid; grid-template-columns: max-content 1fr; gap: .1em 1em; }
dl.meta dt { color: #555; } dl.meta dd { margin: 0; overflow-wrap: anywhere; }
table { border-collapse: collapse; margin: .6em 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: .2em .5em; vertical-align: top; }
th { background: #f3f3f3; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
.scroll { overflow-x: auto; }
.agrees { background: #e3f4e1; } .disagrees { background: #fbe3e0; } .neutral { color: #555; }
table.claims { width: 100%; table-layout: fixed; }
table.claims td { overflow-wrap: anywhere; }
table.claims td.measured div + div { margin-top: .35em; }
table.claims td.measured div.headline { font-weight: bold; }
table.claims td.measured details { margin-top: .35em; }
col.c-claim { width: 17%; } col.c-paper { width: 12%; } col.c-measured { width: 43%; }
col.c-verdict { width: 16%; } col.c-rule { width: 12%; }
.outcome-holds { background: #dcf1d8; } .outcome-holds-in-part { background: #f6efc8; }
.outcome-differs, .outcome-refuted { background: #f9dcd7; }
.outcome-inconclusive { background: #ececec; }
td.verdict strong { display: block; }
.legend span { padding: 0 .5em; margin-right: .4em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption, .note { color: #555; font-size: 13px; }
.files a { margin-right: 1em; white-space: nowrap; }
";

/// The `generator` tag, near the top of the page: how a later report recognises an earlier one's
/// folder inside RESULTS and leaves it out.
pub const GENERATOR: &str = "<meta name=\"generator\" content=\"raycost report\">";

/// How to read the claims tables, once at the top.
const READING: &str = "<p class=\"note\">Each experiment's claims are read back from its table \
(NAME.csv: the M_mean, M_se, M_n, M_clusters columns beside M_theory, or M_lower and M_upper for a \
band) and \
judged by the rules of the terminal summary: against a prediction, &ldquo;ok (99% CI)&rdquo; when \
the prediction lies within the 99% confidence interval, else the distance in standard errors; \
against a band, where the 95% interval falls (below, inside, above); n/a without a standard error \
or a finite theory. The interval is Student-t on M_clusters − 1 degrees of freedom, as the run's \
own; tables written before that column existed give only M_n, which is used instead (too narrow \
where few clusters stand behind many samples). \
A single value against a cost model has no standard error: its ratio is shown, with no verdict. \
Details: docs/report.md.</p>\n";

/// The page.
pub fn render(r: &Report) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         {GENERATOR}\n<title>raycost results</title>\n<link rel=\"icon\" href=\"data:,\">\n\
         <style>{CSS}</style>\n</head>\n<body>\n<h1>raycost results</h1>\n\
         <p>{} experiment(s) in <code>{}</code>; page made by raycost {}.</p>\n",
        r.experiments.len(),
        text(&r.results),
        text(&r.made_by)
    );
    s.push_str(READING);
    contents(&mut s, r);
    claims(&mut s, r.claims.as_deref());
    if let Some(b) = &r.bench {
        bench(&mut s, b);
    }
    for e in &r.experiments {
        experiment(&mut s, e);
    }
    for o in &r.others {
        other(&mut s, o);
    }
    s.push_str("</body>\n</html>\n");
    s
}

/// The table of contents.
fn contents(s: &mut String, r: &Report) {
    s.push_str(
        "<nav>\n<h2>Contents</h2>\n<ul>\n<li><a href=\"#claims\">Claims of the papers</a></li>\n",
    );
    if r.bench.is_some() {
        s.push_str("<li><a href=\"#bench\">Speed (raycost bench)</a></li>\n");
    }
    for name in r
        .experiments
        .iter()
        .map(|e| &e.name)
        .chain(r.others.iter().map(|o| &o.name))
    {
        let _ = writeln!(
            s,
            "<li><a href=\"#{}\">{}</a></li>",
            anchor("exp", name),
            text(name)
        );
    }
    s.push_str("</ul>\n</nav>\n");
}

/// The claims file's table, or where to put one.
fn claims(s: &mut String, claims: Option<&[PaperClaim]>) {
    s.push_str("<section id=\"claims\">\n<h2>Claims of the papers</h2>\n");
    let Some(claims) = claims else {
        let _ = writeln!(
            s,
            "<p class=\"note\">No <code>{}</code> in the results folder; its format is in \
             docs/report.md.</p>\n</section>",
            super::claims::FILE
        );
        return;
    };
    s.push_str(
        "<p class=\"note legend\">Verdicts by their meaning: <span class=\"outcome-holds\">holds</span>\
         <span class=\"outcome-holds-in-part\">holds in part</span><span class=\"outcome-differs\">\
         differs or refuted</span><span class=\"outcome-inconclusive\">inconclusive</span> \
         (the rules: claims/preregistered.toml).</p>\n<table class=\"claims\">\n<colgroup>\
         <col class=\"c-claim\"><col class=\"c-paper\"><col class=\"c-measured\"><col class=\"c-verdict\">\
         <col class=\"c-rule\"></colgroup>\n<tr><th>claim</th><th>paper</th><th>measured (95% CI)</th>\
         <th>verdict</th><th>rule · accounting · source</th></tr>\n",
    );
    for c in claims {
        let _ = writeln!(
            s,
            "<tr><td>{}<div class=\"note\">{}</div></td><td>{}</td><td class=\"measured\">{}{}{}{}</td>\
             {}<td>{}<a href=\"{}\">{}</a></td></tr>",
            text(&c.claim),
            text(&c.reference),
            text(&c.paper),
            headline_div(&c.headline),
            parts(&c.measured),
            every_unit(&c.units),
            note_div(&c.note),
            verdict_cell(c),
            rule_text(c),
            href(&c.link),
            text(&c.source),
        );
    }
    s.push_str("</table>\n</section>\n");
}

/// A long measured text, one block per part (the parts are joined by " · ").
fn parts(measured: &str) -> String {
    measured
        .split(" · ")
        .map(|p| format!("<div>{}</div>", text(p)))
        .collect()
}

/// The headline (the one number held against the paper's) in bold above every unit's details
/// (nothing when empty).
fn headline_div(headline: &str) -> String {
    if headline.is_empty() {
        String::new()
    } else {
        format!("<div class=\"headline\">{}</div>", text(headline))
    }
}

/// Every judged unit, folded (`measured` shows the first few): nothing when the file lists none.
fn every_unit(units: &[String]) -> String {
    if units.is_empty() {
        return String::new();
    }
    let items: String = units
        .iter()
        .map(|u| format!("<li>{}</li>", text(u)))
        .collect();
    format!(
        "<details><summary>every unit ({})</summary><ul>{items}</ul></details>",
        units.len()
    )
}

/// The claim's note as a block under its measurement (nothing when empty).
fn note_div(note: &str) -> String {
    if note.is_empty() {
        String::new()
    } else {
        format!("<div class=\"note\">{}</div>", text(note))
    }
}

/// The verdict cell: coloured by the typed outcome when the file gives one (`data-outcome` says
/// which, for the browser test), else by the tone of the verdict text.
fn verdict_cell(c: &PaperClaim) -> String {
    match &c.outcome {
        Some(o) => {
            let reason = c
                .verdict
                .strip_prefix(o.as_str())
                .map(|r| r.trim_start_matches(':').trim())
                .unwrap_or(&c.verdict);
            let earlier = if c.earlier.is_empty() {
                String::new()
            } else {
                format!("<div class=\"note\">earlier: {}</div>", text(&c.earlier))
            };
            // `o` is one of claims::OUTCOMES (checked when loaded); escaped all the same.
            let o = text(o);
            format!(
                "<td class=\"verdict outcome-{o}\" data-outcome=\"{o}\"><strong>{o}</strong>{}{earlier}</td>",
                text(reason)
            )
        }
        None => format!(
            "<td class=\"verdict {}\">{}</td>",
            tone(c.tone),
            text(&c.verdict)
        ),
    }
}

/// The rule and accounting of a claim, each followed by a separator (empty when not given).
fn rule_text(c: &PaperClaim) -> String {
    [&c.rule, &c.accounting]
        .iter()
        .filter(|x| !x.is_empty())
        .map(|x| format!("{} · ", text(x)))
        .collect()
}

/// The bench section.
fn bench(s: &mut String, b: &BenchSection) {
    s.push_str("<section id=\"bench\">\n<h2>Speed (raycost bench)</h2>\n");
    match &b.meta {
        Some(m) => meta(s, m, true),
        None => {
            s.push_str("<p class=\"note\">No bench.meta.toml: CPU and load not recorded.</p>\n")
        }
    }
    if let Some(t) = &b.table {
        s.push_str("<div class=\"scroll\"><table>\n<tr>");
        for h in &t.header {
            let _ = write!(s, "<th>{}</th>", text(h));
        }
        s.push_str("</tr>\n");
        for row in &t.rows {
            s.push_str("<tr>");
            for c in row {
                let class = if c.parse::<f64>().is_ok() || c.is_empty() {
                    "num"
                } else {
                    "name"
                };
                let _ = write!(s, "<td class=\"{class}\">{}</td>", text(c));
            }
            s.push_str("</tr>\n");
        }
        s.push_str(
            "</table></div>\n<p class=\"note\">rays_per_s is the median over rounds; every column \
             is in the linked bench.csv.</p>\n",
        );
    }
    files(s, &b.files);
    s.push_str("</section>\n");
}

/// One experiment.
fn experiment(s: &mut String, e: &ExperimentSection) {
    let _ = writeln!(
        s,
        "<section id=\"{}\">\n<h2>{}</h2>",
        anchor("exp", &e.name),
        text(&e.name)
    );
    meta(s, &e.meta, false);
    images(s, &e.files);
    if !e.has_main_table {
        let _ = writeln!(
            s,
            "<p class=\"note\">No {}.csv in this folder.</p>",
            text(&e.name)
        );
    } else if e.points.iter().all(|p| p.claims.is_empty()) {
        s.push_str("<p class=\"note\">No measured column of this table has a theory column.</p>\n");
    } else {
        points(s, &e.points);
    }
    links(s, &e.files);
    s.push_str("</section>\n");
}

/// A folder without metadata.
fn other(s: &mut String, o: &OtherSection) {
    let _ = writeln!(
        s,
        "<section id=\"{}\">\n<h2>{}</h2>\n<p class=\"note\">A folder without metadata (no {}.meta.toml).</p>",
        anchor("exp", &o.name),
        text(&o.name),
        text(&o.name)
    );
    files(s, &o.files);
    s.push_str("</section>\n");
}

/// The provenance list (for the bench, without the spec's rows: it has no spec).
fn meta(s: &mut String, m: &MetaView, bench: bool) {
    let none = "not recorded";
    let opt = |v: &Option<String>| v.clone().unwrap_or_else(|| none.to_string());
    let load = |v: &[f64]| {
        if v.is_empty() {
            none.to_string()
        } else {
            v.iter()
                .map(|x| format!("{x:.2}"))
                .collect::<Vec<_>>()
                .join(" ")
        }
    };
    let mut rows: Vec<(&str, String)> = Vec::new();
    if !bench {
        rows.extend([
            ("kind", opt(&m.kind)),
            ("description", opt(&m.description)),
            ("metadata", m.schema_label()),
            ("spec", opt(&m.spec_path)),
            ("spec hash", opt(&m.spec_hash)),
        ]);
    } else {
        rows.push(("metadata", m.schema_label()));
    }
    rows.extend([
        ("commit", opt(&m.commit)),
        ("CPU", opt(&m.cpu)),
        ("host", opt(&m.host)),
        (
            "threads",
            m.threads.map_or(none.to_string(), |t| t.to_string()),
        ),
        ("started", opt(&m.started)),
        ("finished", opt(&m.finished)),
        (
            "wall",
            m.wall_s.map_or(none.to_string(), |w| format!("{w:.1} s")),
        ),
        ("load average at start (1, 5, 15 min)", load(&m.load_start)),
        ("load average at end", load(&m.load_end)),
    ]);
    s.push_str("<dl class=\"meta\">\n");
    for (k, v) in rows {
        let _ = writeln!(s, "<dt>{}</dt><dd>{}</dd>", text(k), text(&v));
    }
    for w in &m.warnings {
        let _ = writeln!(s, "<dt>warning</dt><dd>{}</dd>", text(w));
    }
    s.push_str("</dl>\n");
}

/// The claims of every point, one row per metric.
fn points(s: &mut String, points: &[PointClaims]) {
    s.push_str(
        "<div class=\"scroll\"><table>\n<tr><th>point</th><th>parameters</th><th>metric</th>\
         <th>measured ± 95% CI</th><th>theory (prediction [band])</th><th>verdict</th></tr>\n",
    );
    for p in points.iter().filter(|p| !p.claims.is_empty()) {
        for (i, c) in p.claims.iter().enumerate() {
            s.push_str("<tr>");
            if i == 0 {
                let span = p.claims.len();
                let _ = write!(
                    s,
                    "<td rowspan=\"{span}\" class=\"num\">{}</td><td rowspan=\"{span}\" class=\"mono\">{}</td>",
                    text(&p.point),
                    text(&p.params)
                );
            }
            let _ = writeln!(
                s,
                "<td class=\"mono\">{}</td><td class=\"num measured\">{}</td><td class=\"num\">{}</td>\
                 <td class=\"{}\">{}</td></tr>",
                text(&c.metric),
                text(&c.measured),
                text(&c.theory),
                tone(c.tone),
                text(&c.verdict)
            );
        }
    }
    s.push_str("</table></div>\n");
}

/// Images, then links.
fn files(s: &mut String, f: &Files) {
    images(s, f);
    links(s, f);
}

/// The images of a folder.
fn images(s: &mut String, f: &Files) {
    for im in &f.images {
        let _ = writeln!(
            s,
            "<figure><img src=\"{}\" alt=\"{}\" width=\"{}\" height=\"{}\"><figcaption>{}</figcaption></figure>",
            href(&im.rel),
            text(&im.name),
            im.size.0,
            im.size.1,
            text(&im.name)
        );
    }
}

/// The links to a folder's tables and other files.
fn links(s: &mut String, f: &Files) {
    for (label, list) in [("Tables", &f.tables), ("Other files", &f.others)] {
        if list.is_empty() {
            continue;
        }
        let _ = write!(s, "<p class=\"files\">{label}: ");
        for l in list.iter() {
            let _ = write!(s, "<a href=\"{}\">{}</a> ", href(&l.rel), text(&l.name));
        }
        s.push_str("</p>\n");
    }
}

/// The CSS class of a tone.
fn tone(t: Tone) -> &'static str {
    match t {
        Tone::Agrees => "agrees",
        Tone::Disagrees => "disagrees",
        Tone::Inconclusive | Tone::NotJudged => "neutral",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claim(outcome: Option<&str>, verdict: &str) -> PaperClaim {
        PaperClaim {
            claim: "Theorem 2".into(),
            reference: "DETP".into(),
            paper: "0.35".into(),
            headline: "crossing 0.29 [0.28, 0.44] <a>".into(),
            units: vec!["octree: 0.29 [0.28, 0.44]".into(), "grid: <none>".into()],
            measured: "0.29 [0.28, 0.44] · beside: seconds <3>".into(),
            verdict: verdict.into(),
            tone: super::super::verdicts::claim_tone(outcome.and_then(|o| o.parse().ok()), verdict),
            outcome: outcome.map(str::to_string),
            rule: "theorem-2/2".into(),
            accounting: "paper".into(),
            earlier: "theorem-2/1: holds in seconds".into(),
            source: "a/a.csv".into(),
            link: "../a/a.csv".into(),
            note: String::new(),
        }
    }

    #[test]
    fn verdict_cells_are_coloured_by_their_outcome() {
        let mut s = String::new();
        claims(
            &mut s,
            Some(&[
                claim(Some("holds"), "holds: 2 of 2 units hold"),
                claim(
                    Some("inconclusive"),
                    "inconclusive: needs detp.index = grid",
                ),
                claim(None, "ok (99% CI)"),
            ]),
        );
        assert!(s.contains(
            "<td class=\"verdict outcome-holds\" data-outcome=\"holds\"><strong>holds</strong>2 of 2 units hold"
        ));
        assert!(s.contains("outcome-inconclusive\" data-outcome=\"inconclusive\""));
        assert!(s.contains(
            "<strong>inconclusive</strong>needs detp.index = grid<div class=\"note\">earlier:"
        ));
        // Without an outcome, the verdict text's tone, as before.
        assert!(s.contains("<td class=\"verdict agrees\">ok (99% CI)</td>"));
        // The headline first, escaped, then the measurement in parts, escaped; the rule and
        // accounting beside the source.
        assert!(s.contains(
            "<td class=\"measured\"><div class=\"headline\">crossing 0.29 [0.28, 0.44] &lt;a&gt;</div><div>0.29"
        ));
        assert!(s.contains(
            "<details><summary>every unit (2)</summary><ul><li>octree: 0.29 [0.28, 0.44]</li>\
             <li>grid: &lt;none&gt;</li></ul></details>"
        ));
        assert!(s.contains("<div>0.29 [0.28, 0.44]</div><div>beside: seconds &lt;3&gt;</div>"));
        assert!(s.contains("theorem-2/2 · paper · <a href="));
        assert!(s.contains("earlier: theorem-2/1: holds in seconds"));
        // Every outcome has a colour in the style sheet.
        for o in super::super::claims::OUTCOMES {
            assert!(CSS.contains(&format!(".outcome-{o}")), "{o}");
        }
    }
}
