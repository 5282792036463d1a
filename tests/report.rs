//! The report: time at equal error read off synthetic curves, the CSV read
//! back, a small sweep end to end (library and command line).

use std::path::{Path, PathBuf};

use crate::common;
use pbgi::render::{ReferenceOptions, RenderOptions, render_reference};
use pbgi::report::{
    ErrorPoint, Method, OIDN_SUFFIX, PATH_TRACER, Reach, ReportError, SweepOptions, default_curves,
    equal_error, equal_error_markdown, error_sweep, external_points, from_csv, summary_header, summary_row,
    time_for, to_csv,
};
use pbgi::scene::builtin::cornell_box;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

/// Between the two points that bracket the error, log(time) is linear in
/// log(error); the first crossing counts, even where the times are not in
/// order (a curve's cost is its spp, and a cheap image may run slower).
#[test]
fn time_for_interpolates_between_the_bracketing_points() {
    // Error ∝ t^-1/2 exactly: every interpolation is exact.
    let curve = [(1.0, 0.08), (4.0, 0.04), (16.0, 0.02)];
    let r = time_for(&curve, 0.04 * 2f64.sqrt()).unwrap();
    assert!(close(r.seconds, 2.0) && !r.extrapolated, "{r:?}");
    let r = time_for(&curve, 0.02 * 2f64.sqrt()).unwrap();
    assert!(close(r.seconds, 8.0) && !r.extrapolated, "{r:?}");
    // Exactly on a point.
    let r = time_for(&curve, 0.04).unwrap();
    assert!(close(r.seconds, 4.0) && !r.extrapolated, "{r:?}");
    // Error ∝ t^-1 between (2, 0.1) and (4, 0.05): 0.075 is at 2·(4/3) s.
    let r = time_for(&[(2.0, 0.1), (4.0, 0.05)], 0.075).unwrap();
    assert!(close(r.seconds, 8.0 / 3.0), "{r:?}");
    // Times out of order: the error still falls along the curve, 6 s → 5 s.
    let r = time_for(&[(6.0, 0.08), (5.0, 0.04), (7.0, 0.02)], 0.04 * 2f64.sqrt()).unwrap();
    assert!(
        close(r.seconds, (6.0f64 * 5.0).sqrt()) && !r.extrapolated,
        "{r:?}"
    );
    // A bump: the first crossing of 3 % is the last segment, not the first.
    let r = time_for(&[(1.0, 0.05), (2.0, 0.04), (4.0, 0.045), (8.0, 0.02)], 0.03).unwrap();
    assert!(r.seconds > 4.0 && r.seconds < 8.0, "{r:?}");
}

/// Beyond the ends, error ∝ 1/√t from the nearest point, marked.
#[test]
fn time_for_extrapolates_beyond_the_ends_and_says_so() {
    let curve = [(1.0, 0.08), (4.0, 0.04)];
    assert_eq!(
        time_for(&curve, 0.02),
        Some(Reach {
            seconds: 16.0,
            extrapolated: true
        })
    );
    assert_eq!(
        time_for(&curve, 0.16),
        Some(Reach {
            seconds: 0.25,
            extrapolated: true
        })
    );
    // One point: both ways.
    let r = time_for(&[(2.0, 0.05)], 0.025).unwrap();
    assert!(close(r.seconds, 8.0) && r.extrapolated);
}

/// A curve whose error stopped falling never reaches an error below it;
/// no usable point, no time.
#[test]
fn a_curve_that_stops_falling_never_reaches_a_lower_error() {
    assert_eq!(time_for(&[(1.0, 0.05), (2.0, 0.03), (4.0, 0.031)], 0.02), None);
    assert_eq!(time_for(&[(1.0, 0.05), (2.0, 0.03), (4.0, 0.03)], 0.02), None);
    // It still reaches what it passed.
    assert!(time_for(&[(1.0, 0.05), (2.0, 0.03), (4.0, 0.031)], 0.04).is_some());
    assert_eq!(time_for(&[], 0.02), None);
    assert_eq!(time_for(&[(0.0, 0.05), (1.0, f64::NAN)], 0.02), None);
    assert_eq!(time_for(&[(1.0, 0.05)], 0.0), None);
}

fn point(method: Method, label: &str, spp: u32, total_s: f64, rel_rmse: f64) -> ErrorPoint {
    ErrorPoint {
        method,
        label: label.into(),
        spp,
        pre_s: 0.125,
        trav_s: 0.5,
        shading_s: 1.5,
        total_s,
        rel_rmse,
        floor: 0.0,
    }
}

/// The table takes, per error, the point-based curve that gets there
/// first, a measured time before an extrapolated one, and divides the path
/// tracer's time by it.
#[test]
fn the_equal_error_table_takes_the_best_curve() {
    use Method::{PathTracer, PointBased};
    let points = [
        // Fast but stuck at 4 %.
        point(PointBased, "sparse", 1, 2.0, 0.06),
        point(PointBased, "sparse", 4, 2.5, 0.04),
        point(PointBased, "sparse", 16, 3.0, 0.04),
        // Slower, keeps falling.
        point(PointBased, "dense", 1, 4.0, 0.05),
        point(PointBased, "dense", 4, 16.0, 0.025),
        // Under 5 % at its first (and only) point, extrapolated to 5 % at
        // 1.92 s: the sparse curve's measured 2.21 s wins all the same.
        point(PointBased, "one point", 4, 3.0, 0.04),
        point(PathTracer, PATH_TRACER, 16, 1.0, 0.1),
        point(PathTracer, PATH_TRACER, 64, 4.0, 0.05),
        point(PathTracer, PATH_TRACER, 256, 16.0, 0.025),
    ];
    let rows = equal_error(&points, &[0.05, 0.03, 0.02]);
    let (label, pb) = rows[0].point_based.clone().unwrap();
    assert_eq!(label, "sparse");
    // 5 % halfway (in log error) from 6 % to 4 % is at 2·(2.5/2)^f s.
    let f = (0.05f64 / 0.06).ln() / (0.04f64 / 0.06).ln();
    assert!(
        close(pb.seconds, 2.0 * 1.25f64.powf(f)) && !pb.extrapolated,
        "{pb:?}"
    );
    assert!(close(rows[0].path_tracer.unwrap().seconds, 4.0));
    let ratio = rows[0].ratio().unwrap();
    assert!(close(ratio.seconds, 4.0 / pb.seconds) && !ratio.extrapolated);
    // 3 %: sparse stopped at 4 %; the one point would get there sooner
    // (5.3 s), but only extrapolated: the dense curve's measured 11 s wins.
    let (label, pb) = rows[1].point_based.clone().unwrap();
    assert_eq!(label, "dense");
    assert!(!pb.extrapolated);
    // 2 %: beyond every curve's end, so the soonest extrapolation: the one
    // point's 3·2² s against the dense curve's 16·1.25² s; the ratio is
    // extrapolated too.
    let (label, pb) = rows[2].point_based.clone().unwrap();
    assert_eq!(label, "one point");
    assert!(close(pb.seconds, 12.0) && pb.extrapolated, "{pb:?}");
    assert!(rows[2].ratio().unwrap().extrapolated);
    // No path tracer: no ratio.
    let rows = equal_error(&points[..6], &[0.05]);
    assert!(rows[0].path_tracer.is_none() && rows[0].ratio().is_none());
}

/// Denoised path tracing is a column of its own: per error its soonest
/// curve (never counted as point-based or as the plain path tracer), and
/// its time over the best point-based one; the Markdown table has both
/// ratios where denoised points exist and keeps its four columns where none
/// do.
#[test]
fn denoised_path_tracing_gets_a_ratio_of_its_own() {
    use Method::{Denoised, PathTracer, PointBased};
    let points = [
        point(PointBased, "defaults", 1, 2.0, 0.06),
        point(PointBased, "defaults", 4, 4.0, 0.02),
        point(PathTracer, PATH_TRACER, 16, 1.0, 0.1),
        point(PathTracer, PATH_TRACER, 256, 16.0, 0.025),
        // Slow and fast denoisers; the fast one at 4 % in 0.5 s, 2 % in 2 s.
        point(Denoised, "slow + OIDN", 4, 3.0, 0.04),
        point(Denoised, "slow + OIDN", 16, 12.0, 0.02),
        point(Denoised, "fast + OIDN", 4, 0.5, 0.04),
        point(Denoised, "fast + OIDN", 16, 2.0, 0.02),
    ];
    let rows = equal_error(&points, &[0.04, 0.02]);
    let (label, dn) = rows[0].denoised.clone().unwrap();
    assert_eq!(label, "fast + OIDN");
    assert!(close(dn.seconds, 0.5) && !dn.extrapolated, "{dn:?}");
    let (label, pb) = rows[1].point_based.clone().unwrap();
    assert_eq!(label, "defaults");
    assert!(close(pb.seconds, 4.0));
    let r = rows[1].ratio_denoised().unwrap();
    assert!(close(r.seconds, 2.0 / 4.0) && !r.extrapolated, "{r:?}");
    // The plain path tracer's ratio is its own curve's, not a denoiser's.
    assert!(close(
        rows[1].path_tracer.unwrap().seconds,
        16.0 * (0.025f64 / 0.02).powi(2)
    ));
    let md = equal_error_markdown(&points, &[0.04, 0.02]);
    assert!(md.contains("| denoised / point-based |"), "{md}");
    assert!(
        md.contains("| 2 % | ~25.0 s | 2.00 s (fast + OIDN) | 4.00 s (defaults) | ~6.25× | 0.50× |"),
        "{md}"
    );
    let md = equal_error_markdown(&points[..4], &[0.02]);
    assert!(!md.contains("denoised"), "{md}");
}

/// The README's row: the plain curve's error and time at the default spp,
/// then per error the soonest plain curve, the soonest one through OIDN and
/// the soonest denoised path tracing, kept apart.
#[test]
fn the_summary_row_keeps_pbgi_its_denoised_curves_and_mitsuba_apart() {
    use Method::{Denoised, PathTracer, PointBased};
    let points = [
        point(PointBased, "defaults", 1, 2.0, 0.06),
        point(PointBased, "defaults", 4, 4.0, 0.02),
        // Through OIDN: 4 % at 1 spp, so 4 % sooner than the plain curve.
        point(PointBased, &format!("defaults{OIDN_SUFFIX}"), 1, 2.5, 0.04),
        point(PointBased, &format!("defaults{OIDN_SUFFIX}"), 4, 4.5, 0.03),
        point(PathTracer, PATH_TRACER, 16, 1.0, 0.1),
        point(Denoised, "Mitsuba 3 + OIDN", 4, 0.5, 0.04),
        point(Denoised, "Mitsuba 3 + OIDN", 16, 2.0, 0.03),
    ];
    let header = summary_header(4, &[0.04, 0.02]);
    assert!(header.starts_with("| scene | pbgi at 4 spp: error, time | seconds to 4 / 2 %: pbgi |"));
    let row = summary_row("box", &points, &[0.04, 0.02], 4);
    // Plain: 4 % between 2 s (6 %) and 4 s (2 %); 2 % at its last point.
    let f = (0.04f64 / 0.06).ln() / (0.02f64 / 0.06).ln();
    let at_4 = 2.0 * 2f64.powf(f);
    assert_eq!(
        row,
        format!("| box | 2.00 %, 4.00 s | {at_4:.1} / 4.0 s | 2.5 / — s | 0.50 / — s |"),
    );
    // Without denoised curves, their columns say so.
    let row = summary_row("box", &points[..2], &[0.04], 4);
    assert_eq!(row, format!("| box | 2.00 %, 4.00 s | {at_4:.1} s | n/a | n/a |"));
    // A default spp the sweep lacks is not made up.
    assert!(summary_row("box", &points[..2], &[0.04], 8).starts_with("| box | n/a |"));
}

/// The list `scripts/denoised.py` writes reads back; a bad line is an error
/// naming its number.
#[test]
fn the_list_of_denoised_images_reads_back() {
    let text = "label,spp,seconds,image\n\"Mitsuba 3 + OIDN\",16,0.520000,mitsuba-16.exr\n\n\
                \"pbgi path tracer + OIDN\",64,1.250000,pbgi-64.exr\n";
    let e = external_points(text).unwrap();
    assert_eq!(e.len(), 2);
    assert_eq!(
        (e[1].label.as_str(), e[1].spp, e[1].seconds),
        ("pbgi path tracer + OIDN", 64, 1.25)
    );
    assert_eq!(e[1].image, "pbgi-64.exr");
    let line = |from: &str, to: &str| match external_points(&text.replacen(from, to, 1)) {
        Err(ReportError::Csv { line, what, .. }) => (line, what),
        other => panic!("{from} → {to}: {other:?}"),
    };
    assert_eq!(line(",64,", ",0,"), (4, "bad spp"));
    assert_eq!(line("0.520000", "nan"), (2, "seconds not a positive number"));
    assert_eq!(line(",mitsuba-16.exr", ""), (2, "expected 4 fields"));
    assert_eq!(
        line("label,spp", "spp,label"),
        (1, "not the header label,spp,seconds,image")
    );
}

/// What `to_csv` writes, `from_csv` reads back to the same points (times
/// in micro-seconds), a label with a comma and a quote included; a bad line
/// is an error naming its number.
#[test]
fn the_csv_reads_back_what_it_wrote() {
    let mut points = vec![
        point(Method::PointBased, "defaults", 1, 6.25, 0.0763),
        point(Method::PointBased, "Ω 0.02, \"dense\" gathers", 4, 14.5, 0.0284),
        point(Method::PathTracer, PATH_TRACER, 1024, 50.125, 0.0231),
        point(Method::Denoised, "Mitsuba 3 + OIDN", 64, 0.75, 0.0312),
    ];
    points[1].floor = 0.0125;
    let text = to_csv("box, small", &points);
    let (scene, back) = from_csv(&text).unwrap();
    assert_eq!(scene, "box, small");
    assert_eq!(back, points);
    assert_eq!(to_csv(&scene, &back), text);

    let line2 = |text: &str, from: &str, to: &str| {
        let broken = text.replacen(from, to, 1);
        match from_csv(&broken) {
            Err(ReportError::Csv { line, what, .. }) => (line, what),
            other => panic!("{from} → {to}: {other:?}"),
        }
    };
    assert_eq!(line2(&text, ",pbgi,", ",warp,"), (2, "unknown method"));
    assert_eq!(line2(&text, ",1,", ",one,"), (2, "bad spp"));
    assert_eq!(line2(&text, "6.250000", "inf"), (2, "not a finite number"));
    assert_eq!(line2(&text, "gathers\",", "gathers,"), (3, "a quote left open"));
    assert_eq!(line2(&text, ",defaults,", ",a,b,"), (2, "expected 10 fields"));
    assert_eq!(
        line2(&text, "scene,", "place,"),
        (1, "not the header of an error sweep's CSV")
    );
}

/// The committed reports (`pbgi report`, docs/accuracy.md) read back and write the
/// same CSV; the same with the `floor` column cut off (the nine fields
/// written before points kept their floor) reads with floor 0.
#[test]
fn the_committed_error_sweeps_read_back() {
    for (scene_name, with_floor) in [("cornell-box", true), ("nave", true)] {
        let path = format!("{}/docs/{scene_name}/error.csv", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(path).unwrap();
        let (scene, points) = from_csv(&text).unwrap();
        assert_eq!(scene, scene_name);
        assert!(points.iter().any(|p| p.method == Method::PathTracer));
        assert!(points.iter().filter(|p| p.method == Method::PointBased).count() > 5);
        assert_eq!(points.iter().any(|p| p.floor > 0.0), with_floor);
        let again = to_csv(&scene, &points);
        if with_floor {
            assert_eq!(again, text);
        }
        assert_eq!(from_csv(&again).unwrap(), (scene, points.clone()));
        let nine: String = text
            .lines()
            .map(|l| format!("{}\n", &l[..l.rfind(',').unwrap()]))
            .collect();
        let (_, old) = from_csv(&nine).unwrap();
        assert_eq!(old.len(), points.len());
        assert!(old.iter().all(|p| p.floor == 0.0));
        assert!(old.iter().zip(&points).all(|(a, b)| a.rel_rmse == b.rel_rmse));
    }
}

/// A curve whose error has a floor (its mean offset, a bias) is
/// extrapolated along error² = floor² + c/t and never reaches an error at
/// or below the floor, where 1/√t would claim it; nor below the floor its
/// last two points leave when their error falls slower than 1/√spp.
#[test]
fn a_curve_never_reaches_an_error_below_its_floor() {
    use Method::PointBased;
    // Noise alone from 1 to 4 spp (the error halves), but a mean offset.
    let mut points = [
        point(PointBased, "biased", 1, 1.0, 0.07),
        point(PointBased, "biased", 4, 4.0, 0.035),
    ];
    points[1].floor = 0.03;
    let rows = equal_error(&points, &[0.04, 0.032, 0.03, 0.02]);
    let reach = |k: usize| rows[k].point_based.as_ref().map(|(_, r)| *r);
    assert!(!reach(0).unwrap().extrapolated);
    let r = reach(1).unwrap();
    let want = 4.0 * (0.035f64.powi(2) - 0.03f64.powi(2)) / (0.032f64.powi(2) - 0.03f64.powi(2));
    assert!(close(r.seconds, want) && r.extrapolated, "{r:?} against {want}");
    assert_eq!((reach(2), reach(3)), (None, None));
    // Without the floor: 1/√t from the last point.
    points[1].floor = 0.0;
    let rows = equal_error(&points, &[0.02]);
    let r = rows[0].point_based.as_ref().unwrap().1;
    assert!(close(r.seconds, 4.0 * (0.035f64 / 0.02).powi(2)), "{r:?}");
    // No mean offset, but an error that falls slower than 1/√spp: the
    // floor its two points leave, error² = 0.0008 + 0.0017/spp.
    points[0].rel_rmse = 0.05;
    let floor = 0.0008f64.sqrt();
    let rows = equal_error(&points, &[0.03, floor]);
    let r = rows[0].point_based.as_ref().unwrap().1;
    let want = 4.0 * (0.035f64.powi(2) - floor * floor) / (0.03f64.powi(2) - floor * floor);
    assert!(close(r.seconds, want) && r.extrapolated, "{r:?} against {want}");
    assert!(rows[1].point_based.is_none());
}

/// A whole sweep on a 16 × 16 Cornell box: every image measured, grouped
/// by curve, cheapest first; the path tracer's error falls with its spp; a
/// reference of the wrong size, or a point of 0 spp, stops it before any
/// image.
#[test]
fn a_small_sweep_measures_every_curve() {
    let mut scene = cornell_box();
    scene.camera.width = 16;
    scene.camera.height = 16;
    let o = ReferenceOptions {
        spp: 1024,
        ..Default::default()
    };
    let reference = render_reference(&scene, &o, &|_, _| {}).unwrap().image;
    let base = RenderOptions::default();
    let opts = SweepOptions {
        curves: default_curves(&base, &[1, 4], scene.has_emitters()),
        path_tracer_spp: vec![4, 64],
        bounces: base.bounces,
    };
    let labels: Vec<&str> = opts.curves.iter().map(|c| c.label.as_str()).collect();
    // The second curve is at 0.4 of the defaults' Ω.
    let small = format!(
        "Ω {}",
        ((f64::from(base.cut.max_solid_angle) * 0.4 * 1e4).round() / 1e4) as f32
    );
    // An area light: the base and the coarse gather again at two direct
    // samples per camera sample, from 8 spp on; without one those curves
    // would repeat the others' images.
    assert_eq!(
        labels,
        [
            "defaults",
            small.as_str(),
            "dense gathers",
            "Ω 0.5, N 8",
            "N 10",
            "2 direct samples",
            "Ω 0.5, N 8, 2 direct samples"
        ]
    );
    let unlit: Vec<String> = default_curves(&base, &[1, 4], false)
        .into_iter()
        .map(|c| c.label)
        .collect();
    assert_eq!(
        unlit,
        ["defaults", small.as_str(), "dense gathers", "Ω 0.5, N 8", "N 10"]
    );
    let last = std::sync::Mutex::new(None);
    let points = error_sweep(&scene, &reference, &opts, &|p| {
        *last.lock().unwrap() = Some(p.clone())
    })
    .unwrap();
    let last = last.into_inner().unwrap().unwrap();
    assert_eq!((last.done, last.images, last.remaining_s), (19, 19, Some(0.0)));
    let order: Vec<(&str, u32)> = points.iter().map(|p| (p.label.as_str(), p.spp)).collect();
    assert_eq!(
        order,
        [
            ("defaults", 1),
            ("defaults", 4),
            ("defaults", 8),
            ("defaults", 16),
            (small.as_str(), 4),
            ("dense gathers", 1),
            ("dense gathers", 4),
            ("Ω 0.5, N 8", 1),
            ("Ω 0.5, N 8", 4),
            ("Ω 0.5, N 8", 8),
            ("Ω 0.5, N 8", 16),
            ("N 10", 8),
            ("N 10", 16),
            ("2 direct samples", 8),
            ("2 direct samples", 16),
            ("Ω 0.5, N 8, 2 direct samples", 8),
            ("Ω 0.5, N 8, 2 direct samples", 16),
            (PATH_TRACER, 4),
            (PATH_TRACER, 64)
        ]
    );
    for p in &points {
        assert!(
            p.rel_rmse.is_finite() && p.rel_rmse > 0.0 && p.total_s > 0.0,
            "{p:?}"
        );
    }
    // The path tracer's two points come last.
    let paths = &points[points.len() - 2..];
    assert!(paths[1].rel_rmse < 0.6 * paths[0].rel_rmse, "{paths:?}");

    let mut small = reference.clone();
    small.width = 8;
    small.pixels.truncate(8 * 16);
    let err = error_sweep(&scene, &small, &opts, &|_| {}).unwrap_err();
    assert!(matches!(err, ReportError::ReferenceSize { .. }));
    let msg = err.to_string();
    assert!(msg.contains("8×16") && msg.contains("16×16"), "{msg}");
    let zero = SweepOptions {
        path_tracer_spp: vec![4, 0],
        ..opts
    };
    let err = error_sweep(&scene, &reference, &zero, &|_| {
        panic!("no image before the check")
    })
    .unwrap_err();
    assert!(err.to_string().contains(PATH_TRACER), "{err}");
}

/// The measured Cornell box at 24 × 16 pixels (its meshes from tests/data).
#[cfg(feature = "cli")]
fn small_scene(dir: &Path) -> PathBuf {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cornell-box");
    let xml = std::fs::read_to_string(data.join("cbox.xml")).unwrap();
    let meshes = format!("{}/", data.join("meshes").display());
    let xml = xml
        .replace("name=\"resx\" value=\"256\"", "name=\"resx\" value=\"24\"")
        .replace("name=\"resy\" value=\"256\"", "name=\"resy\" value=\"16\"")
        .replace("value=\"meshes/", &format!("value=\"{meshes}"));
    assert!(xml.contains("value=\"24\"") && xml.contains("value=\"16\""));
    let path = dir.join("small.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

/// `pbgi report` end to end on a small scene: it path traces the missing
/// reference, sweeps, prints the equal-error table and writes the four
/// files; `--replot` redraws from the CSV; two references are averaged; a
/// reference of another size is refused with both sizes named.
#[cfg(feature = "cli")]
#[test]
fn the_cli_report_runs_end_to_end() {
    let dir =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pbgi-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_scene(&dir);
    let out_dir = dir.join("out");
    let run = |args: &[&str]| {
        let o = common::pbgi_command().arg("report").args(args).output().unwrap();
        let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        (o.status.success(), text)
    };
    let (scene_s, out_s) = (scene.to_str().unwrap(), out_dir.to_str().unwrap());
    let (ok, text) = run(&[
        scene_s,
        "--out",
        out_s,
        "--reference-spp",
        "256",
        "--spp",
        "1,4",
        "--path-tracer-spp",
        "4,16",
    ]);
    assert!(ok, "{text}");
    assert!(text.contains("path traced at 256 spp"), "{text}");
    assert!(
        text.contains("| 5 % |") && text.contains("path tracer / point-based"),
        "{text}"
    );
    for f in ["reference.exr", "error.csv", "error.md", "error.png", "error.svg"] {
        assert!(out_dir.join(f).is_file(), "{f} missing:\n{text}");
    }
    let md = std::fs::read_to_string(out_dir.join("error.md")).unwrap();
    assert!(
        md.contains("### Time to reach an error") && md.contains("| dense gathers | 4 |"),
        "{md}"
    );
    std::fs::remove_file(out_dir.join("error.png")).unwrap();
    let (ok, text) = run(&["--replot", "--out", out_s]);
    assert!(ok && text.contains("| 2 % |"), "{text}");
    assert!(out_dir.join("error.png").is_file());

    // Two references are averaged, and the table says so with their noise:
    // the same image twice has none.
    let reference = out_dir.join("reference.exr");
    let r = reference.to_str().unwrap();
    // A one-point sweep with `extra` options.
    let small = |extra: &[&str]| {
        let mut args = vec![scene_s, "--out", out_s, "--spp", "1", "--path-tracer-spp", "4"];
        args.extend_from_slice(extra);
        run(&args)
    };
    let (ok, text) = small(&["--reference", r, "--reference", r]);
    assert!(ok, "{text}");
    let md = std::fs::read_to_string(out_dir.join("error.md")).unwrap();
    assert!(
        md.contains("the mean of") && md.contains("its own noise about 0.00 %"),
        "{md}"
    );

    // Denoised path tracing made beforehand joins the table with a ratio of
    // its own; a list naming a missing image is refused before the sweep,
    // naming the list and the image.
    let dn = dir.join("denoised");
    std::fs::create_dir_all(&dn).unwrap();
    let o = common::pbgi_command()
        .args(["reference", scene_s, "--spp", "4", "--seed", "3", "-o"])
        .arg(dn.join("pt-4.exr"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let list = dn.join("denoised.csv");
    std::fs::write(&list, "label,spp,seconds,image\n\"a denoiser\",4,0.5,pt-4.exr\n").unwrap();
    let report_with = |list: &Path| small(&["--reference", r, "--denoised", list.to_str().unwrap()]);
    let (ok, text) = report_with(&list);
    assert!(ok, "{text}");
    assert!(
        text.contains("denoised / point-based") && text.contains("| a denoiser |"),
        "{text}"
    );
    let csv = std::fs::read_to_string(out_dir.join("error.csv")).unwrap();
    assert!(csv.contains(",denoised,a denoiser,4,"), "{csv}");
    let missing = dn.join("missing.csv");
    std::fs::write(&missing, "label,spp,seconds,image\nx,4,0.5,nowhere.exr\n").unwrap();
    let (ok, text) = report_with(&missing);
    assert!(
        !ok && text.contains("missing.csv") && text.contains("nowhere.exr"),
        "{text}"
    );

    let (ok, text) = run(&[
        "cornell-box",
        "--reference",
        reference.to_str().unwrap(),
        "--out",
        out_s,
    ]);
    assert!(!ok);
    assert!(text.contains("24×16") && text.contains("256×256"), "{text}");

    // `pbgi compare`: an image of another scene than `--scene` (the Cornell
    // box by default) is refused naming the file, both sizes and the option.
    let compare = |args: &[&str]| {
        let o = common::pbgi_command().arg("compare").args(args).output().unwrap();
        let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        (o.status.success(), text)
    };
    let r = reference.to_str().unwrap();
    let (ok, text) = compare(&[r, r]);
    assert!(!ok);
    assert!(
        text.contains("reference.exr: 24×16 pixels") && text.contains("256×256") && text.contains("--scene"),
        "{text}"
    );
    let (ok, text) = compare(&["--scene", scene_s, r, r]);
    assert!(ok && text.contains("relative RMSE 0.0000"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}
