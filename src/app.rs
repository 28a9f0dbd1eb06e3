//! Glue between the parsed command line and the library: one function per subcommand.

use std::io::Write;

use anyhow::Context;

use crate::cli::{Cli, Command, EyeArg, TheoryCommand};
use crate::error::Error;
use crate::experiment::plan::Plan;
use crate::experiment::runner::{self, RunOptions};
use crate::sample::radius::{RadiusClass, RadiusDist, RadiusDraw};
use crate::theory::grid::{self as th, Eye, GridTheoryInput};

/// Runs a parsed command line.
pub fn run(cli: Cli) -> crate::error::Result<()> {
    match cli.command {
        Command::Run(a) => run_spec(a),
        Command::Check(a) => {
            let plan = Plan::load(&a.spec, &a.set, thread_pool(None)?)?;
            let text = if a.json {
                json_text(&plan.describe_json())
            } else {
                plan.describe()
            };
            write!(std::io::stdout().lock(), "{text}")?;
            Ok(())
        }
        Command::Theory(t) => match t.which {
            TheoryCommand::Grid(g) => theory_grid(&g),
            TheoryCommand::Detp(d) => theory_detp(&d),
        },
        Command::Doc(d) => {
            let text = match d.what {
                crate::cli::DocTopic::Kinds => crate::experiment::reference::kinds(),
                crate::cli::DocTopic::Columns => crate::experiment::reference::columns(),
                crate::cli::DocTopic::Spec => crate::experiment::reference::spec(),
                crate::cli::DocTopic::Scene => crate::experiment::reference::scene(),
            };
            write!(std::io::stdout().lock(), "{text}")?;
            Ok(())
        }
        Command::Report(r) => {
            let page = crate::report::run(&crate::report::ReportOptions {
                results: r.results,
                out: r.out,
                force: r.force,
            })?;
            writeln!(std::io::stdout().lock(), "wrote {}", page.display())?;
            Ok(())
        }
        Command::Completions(c) => {
            use clap::CommandFactory;
            let mut cmd = Cli::command();
            clap_complete::generate(c.shell, &mut cmd, "raycost", &mut std::io::stdout().lock());
            Ok(())
        }
        Command::Man => {
            use clap::CommandFactory;
            clap_mangen::Man::new(Cli::command()).render(&mut std::io::stdout().lock())?;
            Ok(())
        }
        Command::Bench(b) => {
            thread_pool(b.threads)?;
            Ok(crate::bench::run(b.quick, &b.out, b.force)?)
        }
        Command::Merge(m) => {
            let photon = crate::experiment::photon_shards::files(&m.inputs);
            if photon.is_empty() {
                return Ok(crate::output::merge::run(
                    &m.inputs,
                    m.out.as_deref(),
                    m.force,
                    m.quiet,
                )?);
            }
            if m.out.is_some() {
                return Err(crate::error::Error::usage(
                    "--out: photon shards merge into NAME.csv beside them (as the unsplit run writes it)",
                ));
            }
            let threads = thread_pool(None)?;
            let (written, summary) =
                crate::experiment::photon_shards::merge(&photon, m.force, m.quiet, threads)?;
            print_run(m.quiet, &summary, &written)
        }
        Command::Render(r) => render(r),
        Command::Reproduce(r) => reproduce(r),
        Command::Crossover(c) => {
            let written = crate::crossover::run(&crate::crossover::Options {
                fronts: c.fronts,
                points: c.points,
                frames: c.frames,
                confirm: c.confirm,
                targets: c.targets,
                out: c.out,
                force: c.force,
            })?;
            let mut out = std::io::stdout().lock();
            for p in written {
                writeln!(out, "wrote {}", p.display())?;
            }
            Ok(())
        }
    }
}

/// `raycost reproduce`: the report on stdout, exit 1 when something counted differs.
fn reproduce(a: crate::cli::ReproduceArgs) -> crate::error::Result<()> {
    let threads = thread_pool(
        a.threads
            .or_else(|| crate::reproduce::recorded_threads(&a.dir)),
    )?;
    let report = crate::reproduce::run(&crate::reproduce::Options {
        dir: a.dir,
        out: a.out,
        threads,
        force: a.force,
        judge_timings: a.timings == crate::cli::Timings::Judge,
        check_only: a.check,
    })?;
    let text = if a.json {
        json_text(&report.json())
    } else {
        report.text()
    };
    write!(std::io::stdout().lock(), "{text}")?;
    if report.same() {
        Ok(())
    } else {
        Err(Error::CheckFailed(report.verdict()))
    }
}

/// `raycost run`.
fn run_spec(a: crate::cli::RunArgs) -> crate::error::Result<()> {
    let threads = thread_pool(a.threads)?;
    if a.set.iter().any(|s| set_key(s) == "experiment.run") {
        return Err(Error::usage(
            "--set experiment.run: give --run R (or --repeat K) instead, so the run's results get their own folder",
        ));
    }
    if let Some(k) = a.repeat {
        return repeat(&a, threads, k);
    }
    let mut sets = a.set.clone();
    sets.extend(a.run.map(|r| format!("experiment.run={r}")));
    let plan = Plan::load(&a.spec, &sets, threads)?;
    let opts = RunOptions {
        out: a.out,
        force: a.force,
        resume: a.resume,
        quiet: a.quiet,
        shard: a.shard,
        sets: a.set,
        threads,
        run: a.run,
        merged: None,
    };
    let (written, summary) = match a.photon_shard {
        None => runner::run(&plan, &opts)?,
        Some(s) => {
            let (path, line) = crate::experiment::photon_shards::run_shard(&plan, &opts, s)?;
            (vec![path], line)
        }
    };
    print_run(a.quiet, &summary, &written)
}

/// A run's summary and the files it wrote (nothing with `--quiet`).
fn print_run(
    quiet: bool,
    summary: &str,
    written: &[std::path::PathBuf],
) -> crate::error::Result<()> {
    if !quiet {
        let mut out = std::io::stdout().lock();
        write!(out, "{summary}")?;
        for p in written {
            writeln!(out, "wrote {}", p.display())?;
        }
    }
    Ok(())
}

/// The key of a `--set KEY=VALUE` flag, as written (spaces and quotes trimmed).
fn set_key(flag: &str) -> String {
    let key = flag.split_once('=').map_or(flag, |(k, _)| k);
    key.trim().replace(['"', '\'', ' '], "")
}

/// `raycost run --repeat K`: runs 0 … K−1, each a separate process of this binary with `--run R`
/// and the other flags as given (so each run is exactly what `--run R` alone gives). The spec is
/// validated here first, so bad input is refused before any run starts.
fn repeat(a: &crate::cli::RunArgs, threads: usize, k: u64) -> crate::error::Result<()> {
    let mut sets = a.set.clone();
    sets.push("experiment.run=0".into());
    Plan::load(&a.spec, &sets, threads)?;
    let exe = std::env::current_exe().context("could not find this raycost binary to repeat it")?;
    for r in 0..k {
        let mut cmd = std::process::Command::new(&exe);
        cmd.arg("run").arg(&a.spec).arg("--out").arg(&a.out);
        cmd.args(["--run", &r.to_string(), "--threads", &threads.to_string()]);
        for s in &a.set {
            cmd.args(["--set", s]);
        }
        if let Some(s) = a.shard {
            cmd.args(["--shard", &format!("{}/{}", s.k, s.n)]);
        }
        for (on, flag) in [
            (a.force, "--force"),
            (a.quiet, "--quiet"),
            (a.resume, "--resume"),
        ] {
            if on {
                cmd.arg(flag);
            }
        }
        let status = cmd
            .status()
            .with_context(|| format!("could not start run {r} of {k}"))?;
        match status.code() {
            Some(0) => {}
            Some(130) => {
                return Err(Error::Interrupted(format!(
                    "run {r} of {k} was interrupted (runs before it are complete); continue it with --run {r} --resume, then the runs after it"
                )))
            }
            code => {
                return Err(Error::internal(format!(
                    "run {r} of {k} failed (exit {}); its message is above",
                    code.map_or("by a signal".into(), |c| c.to_string())
                )))
            }
        }
    }
    Ok(())
}

/// `raycost theory grid`.
fn theory_grid(g: &crate::cli::GridTheoryArgs) -> crate::error::Result<()> {
    for (name, v) in [
        ("--intensity", g.intensity),
        ("--radius", g.radius),
        ("--cell-width", g.cell_width),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Usage(format!(
                "{name}: got {v}, expected a finite number > 0"
            )));
        }
    }
    let classes = [RadiusClass {
        fraction: 1.0,
        radius: RadiusDist::Constant(g.radius),
    }];
    let inp = GridTheoryInput {
        intensity: g.intensity,
        classes: &classes,
        draw: RadiusDraw::PerSphere,
        cell_width: g.cell_width,
    };
    let eye = match g.eye {
        EyeArg::Corner => Eye::Corner,
        EyeArg::Uniform => Eye::Uniform,
    };
    let text = if g.json {
        json_text(&grid_theory_json(&inp, eye))
    } else {
        grid_theory_table(&inp, eye)
    };
    write!(std::io::stdout().lock(), "{text}")?;
    Ok(())
}

/// `raycost theory detp`.
fn theory_detp(d: &crate::cli::DetpTheoryArgs) -> crate::error::Result<()> {
    let ok = |name: &str, v: f64, good: bool, want: &str| {
        if good {
            Ok(())
        } else {
            Err(Error::Usage(format!("{name}: got {v}, expected {want}")))
        }
    };
    let count = |v: f64| v.is_finite() && v >= 1.0;
    ok("--rays", d.rays, count(d.rays), "a count ≥ 1")?;
    ok("--points", d.points, count(d.points), "a count ≥ 1")?;
    ok("--q", d.q, d.q > 0.0 && d.q < 1.0, "a ratio in (0, 1)")?;
    ok(
        "--ratio",
        d.ratio,
        d.ratio > 0.0 && d.ratio <= 1.0,
        "r_D/r_0 in (0, 1]",
    )?;
    ok(
        "--threshold",
        d.threshold,
        count(d.threshold),
        "a count ≥ 1",
    )?;
    let text = if d.json {
        json_text(&detp_theory_json(d))
    } else {
        detp_theory_table(d)
    };
    write!(std::io::stdout().lock(), "{text}")?;
    Ok(())
}

/// `raycost render`.
fn render(r: crate::cli::RenderArgs) -> crate::error::Result<()> {
    let threads = thread_pool(r.threads)?;
    let plan = Plan::load(&r.spec, &r.set, threads)?;
    let frames = match (r.frame, r.frames.is_empty()) {
        (Some(f), _) => vec![f],
        (None, true) => vec![0],
        (None, false) => r.frames,
    };
    let opts = crate::render::RenderOptions {
        frames,
        point: r.point,
        out: r.out,
        gif: r.gif,
        diff: r.diff,
        width: r.width,
        colormap: r.colormap,
        force: r.force,
        eye: vec3("--eye", &r.eye)?,
        look_at: vec3("--look-at", &r.look_at)?,
        fov: r.fov,
        compare_edge: r
            .compare_edge
            .as_deref()
            .map(crate::render::edge_mode)
            .transpose()?,
    };
    let log = crate::render::run(&plan, &opts)?;
    write!(std::io::stdout().lock(), "{log}")?;
    Ok(())
}

/// Pretty JSON with a final newline.
fn json_text(v: &serde_json::Value) -> String {
    let mut s = serde_json::to_string_pretty(v).expect("a JSON value serializes");
    s.push('\n');
    s
}

/// Starts the global thread pool with `n` threads (`--threads`), refusing 0 and more than 8 per
/// CPU (which only add scheduling cost, and a huge count takes minutes to start). Returns the
/// number of worker threads, which is then passed to whatever depends on it (memory needs, the
/// metadata, timings), never read back from the pool; without `--threads`, rayon's default pool
/// size.
fn thread_pool(n: Option<usize>) -> crate::error::Result<usize> {
    let Some(n) = n else {
        return Ok(rayon::current_num_threads());
    };
    if n == 0 {
        return Err(Error::Usage("--threads must be at least 1".into()));
    }
    let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
    if n > 8 * cpus {
        return Err(Error::Usage(format!(
            "--threads: got {n}, this machine has {cpus} logical CPU(s); at most {}",
            8 * cpus
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .context("could not start the thread pool")?;
    Ok(n)
}

/// An optional point given as X,Y,Z.
fn vec3(flag: &str, v: &[f64]) -> crate::error::Result<Option<glam::DVec3>> {
    match v {
        [] => Ok(None),
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Some(glam::DVec3::new(*x, *y, *z))),
        _ => Err(Error::Usage(format!(
            "{flag}: expected three finite numbers X,Y,Z, got {v:?}"
        ))),
    }
}

/// One row of a theory table: a stable name (the JSON key), the table's label, the value.
pub type TheoryRow = (&'static str, &'static str, f64);

/// The closed forms of `theory::detp` for one parameter set (costs in tests, t = u = 1), and the
/// rays per level `(i, r_i/r_0, rays)` while a sphere holds at least `threshold` rays.
pub fn detp_theory_rows(d: &crate::cli::DetpTheoryArgs) -> (Vec<TheoryRow>, Vec<(u32, f64, f64)>) {
    use crate::theory::detp as td;
    let (n_r, n_p, q) = (d.rays, d.points, d.q);
    let (t_r, t_i) = td::sphere_cache_cost(1.0, 1.0, n_r, n_p, q);
    let f_r = td::retraced_rays(n_r, d.ratio);
    let (st_sc, st_di) = td::static_points_cost(f_r, n_p, q);
    let (dy_sc, dy_di) = td::dynamic_points_cost(n_r, d.ratio, n_p, q);
    let rows = vec![
        (
            "sphere_cache_t_r",
            "sphere cache T_R = t·n_R/Q²·(∛n_P − 1)/(1 − Q)",
            t_r,
        ),
        (
            "sphere_cache_t_i",
            "sphere cache T_I = (4/3)·u·n_R·∛n_P",
            t_i,
        ),
        (
            "sphere_cache_t",
            "sphere cache T = T_R + T_I (Theorem 1)",
            t_r + t_i,
        ),
        (
            "disc_index_t",
            "disc indexing T = u·n_R·∛n_P (Theorem 1)",
            td::disc_index_cost(1.0, n_r, n_p),
        ),
        (
            "rebuild_factor",
            "1/(Q²(1 − Q)) (Proposition 1: 6.75 at Q = 2/3)",
            td::rebuild_factor(q),
        ),
        ("optimal_q", "optimal Q (Proposition 1)", td::OPTIMAL_Q),
        (
            "retraced_rays",
            "f_R = n_R·(r_D/r_0)² re-traced rays (eq. 11)",
            f_r,
        ),
        (
            "static_sphere_cache",
            "static points, sphere cache (eq. 13)",
            st_sc,
        ),
        (
            "static_disc_index",
            "static points, disc indexing 2·f_R·∛n (eq. 14)",
            st_di,
        ),
        (
            "dynamic_sphere_cache",
            "dynamic points, sphere cache (eq. 15)",
            dy_sc,
        ),
        (
            "dynamic_disc_index",
            "dynamic points, disc indexing n_R·∛n",
            dy_di,
        ),
        (
            "crossover_ratio_limit",
            "crossover r_D/r_0, n → ∞ (Theorem 2: 0.35)",
            td::crossover_ratio(q, f64::INFINITY),
        ),
        (
            "crossover_ratio",
            "crossover r_D/r_0 at this n_P",
            td::crossover_ratio(q, n_p),
        ),
    ];
    let deepest = td::deepest_level(n_r, q, d.threshold, 1.0, 0.0);
    let levels = (0..=deepest.min(200))
        .map(|i| (i, q.powi(i as i32), td::rays_per_level(n_r, q, i)))
        .collect();
    (rows, levels)
}

/// [`detp_theory_rows`] as a table.
pub fn detp_theory_table(d: &crate::cli::DetpTheoryArgs) -> String {
    let (rows, levels) = detp_theory_rows(d);
    let mut s = format!(
        "DETP theory: n_R = {}, n_P = {}, Q = {}, r_D/r_0 = {}; costs in tests (t = u = 1)\n",
        d.rays, d.points, d.q, d.ratio
    );
    for (_, k, v) in rows {
        s.push_str(&format!("  {k:<52} {v:>16.6e}\n"));
    }
    s.push_str(&format!(
        "  rays per level n_R·Q^(2i), subdivided while ≥ {} rays:\n",
        d.threshold
    ));
    for (i, r, rays) in levels {
        s.push_str(&format!(
            "    level {i:>3}  r_i/r_0 = {r:<12.6e} rays {rays:>14.3}\n"
        ));
    }
    s
}

/// [`detp_theory_rows`] as JSON: the inputs, every value by name, and the levels.
pub fn detp_theory_json(d: &crate::cli::DetpTheoryArgs) -> serde_json::Value {
    let (rows, levels) = detp_theory_rows(d);
    serde_json::json!({
        "theory": "detp",
        "inputs": {
            "rays": d.rays, "points": d.points, "q": d.q, "ratio": d.ratio,
            "threshold": d.threshold,
        },
        "values": rows_json(&rows),
        "levels": levels.iter().map(|&(i, r, rays)| serde_json::json!({
            "level": i, "radius_ratio": r, "rays": rays,
        })).collect::<Vec<_>>(),
    })
}

/// Rows as `{name: {value, label}}`, in table order.
fn rows_json(rows: &[TheoryRow]) -> serde_json::Value {
    serde_json::Value::Object(
        rows.iter()
            .map(|&(name, label, v)| {
                (
                    name.to_string(),
                    serde_json::json!({ "value": v, "label": label }),
                )
            })
            .collect(),
    )
}

/// The closed forms of `theory::grid` for one parameter set.
pub fn grid_theory_rows(inp: &GridTheoryInput, eye: Eye) -> Vec<TheoryRow> {
    let band = th::n_i_band(inp);
    let n_s = th::n_s_mean(inp, eye);
    let r = inp.classes[0].radius.expect(|r| r);
    vec![
        (
            "first_hit_rate",
            "first-hit rate λ = ρπr² (1/length)",
            th::first_hit_rate(inp),
        ),
        ("t_hit", "E[t*] = 1/λ (length)", th::mean_first_hit(inp)),
        (
            "offset_cube_volume",
            "|o(a,r)| offset cube volume",
            th::offset_cube_volume(inp.cell_width, r),
        ),
        ("n_i_lower", "E[N_I] lower (Result 3.1)", band.lower),
        ("n_i_upper", "E[N_I] upper (Result 3.1)", band.upper),
        ("n_s", "E[N_S] (this eye placement)", n_s),
        (
            "n_s_uniform_eye",
            "E[N_S] eye uniform in cell = 1.5·E[t*]/a",
            th::n_s_uniform_eye(inp),
        ),
        (
            "n_s_corner_eye",
            "E[N_S] eye at cell corner",
            th::n_s_corner_eye(inp),
        ),
        (
            "n_i_predictor",
            "E[N_I] predictor, no mailbox",
            th::n_i_predictor(inp, n_s),
        ),
        (
            "n_i_plain_predictor",
            "E[N_I] (1+E[N_S])·ρ|o| (plain)",
            th::n_i_plain_predictor(inp, n_s),
        ),
        (
            "n_i_mb_predictor",
            "E[N_I] predictor, mailboxed",
            th::n_i_mb_predictor(inp, n_s),
        ),
    ]
}

/// [`grid_theory_rows`] as a table.
pub fn grid_theory_table(inp: &GridTheoryInput, eye: Eye) -> String {
    let r = inp.classes[0].radius.expect(|r| r);
    let mut s = format!(
        "grid theory: ρ = {}, r = {r}, a = {}, eye {:?}\n",
        inp.intensity, inp.cell_width, eye
    );
    for (_, k, v) in grid_theory_rows(inp, eye) {
        s.push_str(&format!("  {k:<44} {v:>14.6}\n"));
    }
    s
}

/// [`grid_theory_rows`] as JSON: the inputs and every value by name.
pub fn grid_theory_json(inp: &GridTheoryInput, eye: Eye) -> serde_json::Value {
    serde_json::json!({
        "theory": "grid",
        "inputs": {
            "intensity": inp.intensity,
            "radius": inp.classes[0].radius.expect(|r| r),
            "cell_width": inp.cell_width,
            "eye": format!("{eye:?}").to_lowercase(),
        },
        "values": rows_json(&grid_theory_rows(inp, eye)),
    })
}
