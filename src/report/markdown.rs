//! The report as Markdown: the equal-error tables first (what a reader came
//! for), then every point.

use std::fmt::Write as _;

use super::equal_error::{Reach, Series, equal_error, keep_soonest, series, time_above_floor};
use super::sweep::{ErrorPoint, Method};

/// Seconds to three significant digits.
fn seconds(x: f64) -> String {
    match x {
        x if x >= 100.0 => format!("{x:.0} s"),
        x if x >= 10.0 => format!("{x:.1} s"),
        x if x >= 1.0 => format!("{x:.2} s"),
        x => format!("{x:.3} s"),
    }
}

/// `~` marks a value that rests on an extrapolation.
fn approx(r: &Reach, text: String) -> String {
    if r.extrapolated { format!("~{text}") } else { text }
}

fn percent(e: f64) -> String {
    let v = e * 100.0;
    if (v - v.round()).abs() < 1e-9 {
        format!("{v:.0} %")
    } else {
        format!("{v:.1} %")
    }
}

/// The equal-error table at each of `errors`: the path tracer, the best
/// point-based curve and their ratio; where the sweep has denoised path
/// tracing, its best curve and the ratio against it too. Then every curve's
/// time at each.
pub fn equal_error_markdown(points: &[ErrorPoint], errors: &[f64]) -> String {
    let mut s = String::new();
    let denoised = points.iter().any(|p| p.method == Method::Denoised);
    if denoised {
        let _ = writeln!(
            s,
            "| rel. RMSE | path tracer | denoised path tracing (best) | point-based (best curve) | \
             path tracer / point-based | denoised / point-based |\n\
             | --- | --- | --- | --- | --- | --- |"
        );
    } else {
        let _ = writeln!(
            s,
            "| rel. RMSE | path tracer | point-based (best curve) | path tracer / point-based |\n\
             | --- | --- | --- | --- |"
        );
    }
    let none = || "—".to_string();
    let labelled = |best: &Option<(String, Reach)>| {
        best.as_ref().map_or_else(none, |(label, r)| {
            approx(r, format!("{} ({label})", seconds(r.seconds)))
        })
    };
    let times = |r: Option<Reach>| r.map_or_else(none, |r| approx(&r, format!("{:.2}×", r.seconds)));
    for row in equal_error(points, errors) {
        let pt = row
            .path_tracer
            .map_or_else(none, |r| approx(&r, seconds(r.seconds)));
        let (pb, ratio) = (labelled(&row.point_based), times(row.ratio()));
        if denoised {
            let (dn, ratio_dn) = (labelled(&row.denoised), times(row.ratio_denoised()));
            let _ = writeln!(
                s,
                "| {} | {pt} | {dn} | {pb} | {ratio} | {ratio_dn} |",
                percent(row.error)
            );
        } else {
            let _ = writeln!(s, "| {} | {pt} | {pb} | {ratio} |", percent(row.error));
        }
    }
    let all = series(points);
    let _ = write!(s, "\nTime along each curve:\n\n| rel. RMSE |");
    for c in &all {
        let _ = write!(s, " {} |", c.label);
    }
    let _ = writeln!(s, "\n| --- |{}", " --- |".repeat(all.len()));
    for &e in errors {
        let _ = write!(s, "| {} |", percent(e));
        for c in &all {
            let cell = time_above_floor(&c.time_error(), c.floor, e)
                .map_or_else(none, |r| approx(&r, seconds(r.seconds)));
            let _ = write!(s, " {cell} |");
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "\n~ extrapolated beyond the measured points along error² = floor² + c/t, the floor \
         being the larger of what the last two points leave at infinitely many samples \
         along error² = floor² + c/spp (an error that is no mean offset stays too) and the \
         share of the costliest point's error that its mean offset makes (a bias stays as \
         the noise falls), with the reference's own noise (the path tracer's floor) for the \
         point-based curves; — not reached (at or below that floor, or the curve's error \
         stopped falling above it)."
    );
    s
}

/// The suffix of a point-based curve's label whose images went through
/// Intel OIDN (`pbgi report --denoise`).
pub const OIDN_SUFFIX: &str = " + OIDN";

/// The README's table's header (`docs/expect.md`), for [`summary_row`]'s
/// rows at `errors`.
pub fn summary_header(spp: u32, errors: &[f64]) -> String {
    let at = errors
        .iter()
        .map(|&e| percent(e).trim_end_matches(" %").to_string());
    format!(
        "| scene | pbgi at {spp} spp: error, time | seconds to {} %: pbgi | pbgi + OIDN | \
         Mitsuba 3 + OIDN |\n| --- | --- | --- | --- | --- |",
        at.collect::<Vec<_>>().join(" / ")
    )
}

/// One row of the README's table: `title`, the first point-based curve's
/// error and wall time at `spp`, then the seconds to each of `errors` of
/// the soonest point-based curve, the soonest one through OIDN (labels
/// ending in [`OIDN_SUFFIX`]) and the soonest denoised path tracing (`~`
/// extrapolated, `—` not reached, `n/a` not in the sweep).
pub fn summary_row(title: &str, points: &[ErrorPoint], errors: &[f64], spp: u32) -> String {
    let all = series(points);
    let plain = |c: &Series| c.method == Method::PointBased && !c.label.ends_with(OIDN_SUFFIX);
    let first = all.iter().find(|c| plain(c));
    let at_spp = first
        .and_then(|c| c.points.iter().find(|p| p.0 == spp))
        .map_or("n/a".to_string(), |&(_, t, e)| {
            format!("{}, {}", percent_2(e), seconds(t))
        });
    let column = |keep: &dyn Fn(&Series) -> bool| {
        let curves: Vec<_> = all.iter().filter(|c| keep(c)).collect();
        if curves.is_empty() {
            return "n/a".to_string();
        }
        let cells: Vec<String> = errors
            .iter()
            .map(|&e| {
                let mut best = None;
                for c in &curves {
                    if let Some(r) = time_above_floor(&c.time_error(), c.floor, e) {
                        keep_soonest(&mut best, &c.label, r);
                    }
                }
                best.map_or("—".to_string(), |(_, r)| approx(&r, short_seconds(r.seconds)))
            })
            .collect();
        format!("{} s", cells.join(" / "))
    };
    let pbgi = column(&plain);
    let pbgi_oidn = column(&|c| c.method == Method::PointBased && c.label.ends_with(OIDN_SUFFIX));
    let denoised = column(&|c| c.method == Method::Denoised);
    format!("| {title} | {at_spp} | {pbgi} | {pbgi_oidn} | {denoised} |")
}

/// A relative error in percent to two decimals (`2.91 %`).
fn percent_2(e: f64) -> String {
    format!("{:.2} %", e * 100.0)
}

/// Seconds to two significant digits, without the unit (`0.56`, `2.7`, `14`).
fn short_seconds(x: f64) -> String {
    match x {
        x if x >= 10.0 => format!("{x:.0}"),
        x if x >= 1.0 => format!("{x:.1}"),
        x => format!("{x:.2}"),
    }
}

/// The whole report: a header (`context`: the reference, the settings, the
/// threads, one paragraph), the equal-error tables at `errors`, and every
/// point.
pub fn to_markdown(scene: &str, points: &[ErrorPoint], errors: &[f64], context: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## {scene}: error against run time\n\n{context}\n");
    let _ = writeln!(s, "### Time to reach an error\n");
    s.push_str(&equal_error_markdown(points, errors));
    let _ = writeln!(
        s,
        "\n### Points\n\nTimes in seconds: pre., trav. and shading summed over threads, total wall clock.\n\n\
         | curve | spp | pre. | trav. | shading | total | rel. RMSE |\n\
         | --- | --- | --- | --- | --- | --- | --- |"
    );
    for p in points {
        let _ = match p.method {
            Method::PointBased => writeln!(
                s,
                "| {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} |",
                p.label, p.spp, p.pre_s, p.trav_s, p.shading_s, p.total_s, p.rel_rmse
            ),
            Method::PathTracer | Method::Denoised => writeln!(
                s,
                "| {} | {} | | | | {:.3} | {:.4} |",
                p.label, p.spp, p.total_s, p.rel_rmse
            ),
        };
    }
    s
}
