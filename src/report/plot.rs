//! Error against run time on log-log axes: one line per point-based curve
//! (camera samples per pixel rising along it) and one for the path tracer,
//! with dashed guides at the equal-error table's errors; written as PNG and
//! SVG. Text uses the embedded DejaVu Sans, so no system font is needed.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use super::equal_error::series;
use super::error::ReportError;
use super::sweep::{ErrorPoint, Method};

/// One curve: name, which renderer, and `(seconds, relative RMSE)` points
/// by rising spp.
type Curve = (String, Method, Vec<(f64, f64)>);

fn curves(points: &[ErrorPoint]) -> Vec<Curve> {
    series(points)
        .into_iter()
        .map(|s| {
            let name = match s.method {
                Method::PointBased => format!("pbgi {} (spp sweep)", s.label),
                Method::PathTracer => format!("{} (spp sweep)", s.label),
                Method::Denoised => format!("{} (denoised, spp sweep)", s.label),
            };
            (name, s.method, s.time_error())
        })
        .collect()
}

/// A tick label: at most three significant digits, no float noise.
fn tick(v: &f64) -> String {
    if *v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

const COLORS: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
];

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    curves: &[Curve],
    guides: &[f64],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let all = curves.iter().flat_map(|c| c.2.iter());
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(t, e) in all {
        if t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite() {
            (t0, t1, e0, e1) = (t0.min(t), t1.max(t), e0.min(e), e1.max(e));
        }
    }
    if t0 > t1 {
        return Err("nothing to plot: no point with positive time and error".into());
    }
    let guides: Vec<f64> = guides
        .iter()
        .copied()
        .filter(|&g| g > 0.0 && g.is_finite())
        .collect();
    for &g in &guides {
        (e0, e1) = (e0.min(g), e1.max(g));
    }
    let (x0, x1) = (t0 / 1.5, t1 * 1.5);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), (e0 / 1.3..e1 * 1.3).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time (s, wall clock)")
        .y_desc("relative RMSE")
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let grey = RGBColor(0x90, 0x90, 0x90);
    for &g in &guides {
        chart
            .draw_series(DashedLineSeries::new(
                [(x0, g), (x1, g)],
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{} %", tick(&(g * 100.0))),
                (x0 * 1.05, g * 0.97),
                ("sans-serif", 13).into_font().color(&grey),
            )))
            .map_err(err)?;
    }
    // Path tracing is black (denoised: dark and dashed); each point-based
    // curve has a colour of its own.
    let dark = [RGBColor(0x50, 0x50, 0x50), RGBColor(0x80, 0x60, 0x00)];
    let (mut next, mut next_dark) = (0, 0);
    for (name, method, pts) in curves {
        let color = match method {
            Method::PathTracer => BLACK,
            Method::Denoised => {
                next_dark += 1;
                dark[(next_dark - 1) % dark.len()]
            }
            Method::PointBased => {
                next += 1;
                COLORS[(next - 1) % COLORS.len()]
            }
        };
        let pts: Vec<(f64, f64)> = pts.iter().copied().filter(|&(t, e)| t > 0.0 && e > 0.0).collect();
        curve(&mut chart, name, &pts, color, *method == Method::Denoised)?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
    root.present().map_err(err)?;
    Ok(())
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is valid TrueType; a failure only loses the text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

/// Writes the error-against-time plot of `points` to `png` and `svg`: one
/// line per curve, dashed guides at `guides` (relative RMSE, e.g. the
/// equal-error table's).
pub fn write_plots(
    points: &[ErrorPoint],
    guides: &[f64],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    register_font();
    let curves = curves(points);
    let fail = |path: &Path, message: String| ReportError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let (w, h) = (900u32, 620u32);
    draw(
        SVGBackend::new(svg, (w, h)).into_drawing_area(),
        title,
        &curves,
        guides,
    )
    .map_err(|e| fail(svg, e))?;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area(),
        title,
        &curves,
        guides,
    )
    .map_err(|e| fail(png, e))?;
    image::save_buffer(png, &buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| fail(png, e.to_string()))?;
    Ok(())
}

/// The charts here: log-log.
type LogChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// A line through `pts` (dashed or solid) with a dot at each, in the
/// legend as `name`.
fn curve<'a, DB: DrawingBackend + 'a>(
    chart: &mut LogChart<'a, DB>,
    name: &str,
    pts: &[(f64, f64)],
    color: RGBColor,
    dashed: bool,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let style = color.stroke_width(2);
    let legend = move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style);
    if dashed {
        chart
            .draw_series(DashedLineSeries::new(pts.to_vec(), 8, 4, style))
            .map_err(err)?
            .label(name)
            .legend(legend);
    } else {
        chart
            .draw_series(LineSeries::new(pts.to_vec(), style))
            .map_err(err)?
            .label(name)
            .legend(legend);
    }
    chart
        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
        .map_err(err)?;
    Ok(())
}

/// The legend, boxed, at `position`.
fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut LogChart<'a, DB>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", size))
        .draw()
        .map_err(|e| e.to_string())
}

/// Writes the scale benchmark's plot to `png` and `svg`: wall-clock seconds
/// of each part against the triangles (`by_triangles`, one budget) and
/// against the surfels (`by_surfels`, one mesh), log-log, with the peak
/// memory in GB dashed on the same axis.
pub fn write_scale_plot(
    by_triangles: &[super::ScaleRow],
    by_surfels: &[super::ScaleRow],
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    register_font();
    let fail = |path: &Path, message: String| ReportError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let (w, h) = (1200u32, 520u32);
    scale_panels(
        SVGBackend::new(svg, (w, h)).into_drawing_area(),
        by_triangles,
        by_surfels,
    )
    .map_err(|e| fail(svg, e))?;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    scale_panels(
        BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area(),
        by_triangles,
        by_surfels,
    )
    .map_err(|e| fail(png, e))?;
    image::save_buffer(png, &buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| fail(png, e.to_string()))?;
    Ok(())
}

fn scale_panels<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    by_triangles: &[super::ScaleRow],
    by_surfels: &[super::ScaleRow],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (left, right) = root.split_horizontally(600);
    let budget = by_triangles.first().map_or(0, |r| r.budget);
    let mesh = by_surfels.first().map_or(String::new(), |r| r.label.clone());
    scale_panel(
        left,
        &format!("against triangles ({budget} surfels)"),
        "triangles",
        by_triangles,
        |r| r.triangles as f64,
    )?;
    scale_panel(
        right,
        &format!("against surfels ({mesh})"),
        "surfels",
        by_surfels,
        |r| r.surfels as f64,
    )?;
    root.present().map_err(|e| e.to_string())
}

/// A count's tick label: its power of ten at each decade, else none.
fn decade(v: &f64) -> String {
    let e = v.log10().round();
    if (v / 10f64.powf(e) - 1.0).abs() < 1e-6 {
        let digits = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
        format!(
            "10{}",
            e.to_string()
                .chars()
                .filter_map(|c| c.to_digit(10))
                .map(|d| digits[d as usize])
                .collect::<String>()
        )
    } else {
        String::new()
    }
}

fn scale_panel<DB: DrawingBackend>(
    area: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_desc: &str,
    rows: &[super::ScaleRow],
    x: impl Fn(&super::ScaleRow) -> f64,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    type Part = (&'static str, fn(&super::ScaleRow) -> Option<f64>);
    let parts: [Part; 7] = [
        ("BVH", |r| Some(r.pre.tracer)),
        ("surfels + direct light", |r| Some(r.pre.surfels)),
        ("gathers at surfels", |r| Some(r.pre.gathers)),
        ("tree", |r| Some(r.pre.tree)),
        ("frame", |r| Some(r.frame)),
        ("total", |r| Some(r.total)),
        ("peak memory (GB)", |r| r.peak_bytes.map(|b| b as f64 / 1e9)),
    ];
    let values = || {
        rows.iter()
            .flat_map(|r| parts.iter().filter_map(|(_, f)| f(r)))
            .filter(|v| *v > 0.0 && v.is_finite())
    };
    let (y0, y1) = values().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let (x0, x1) = rows
        .iter()
        .map(&x)
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if y0 > y1 || x0 > x1 {
        return Err(format!("{title}: nothing to plot"));
    }
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("seconds (wall clock); GB dashed")
        .x_label_formatter(&decade)
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    for (i, (name, f)) in parts.iter().enumerate() {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| f(r).map(|v| (x(r), v)))
            .filter(|&(_, v)| v > 0.0)
            .collect();
        let color = if *name == "total" {
            BLACK
        } else {
            COLORS[i % COLORS.len()]
        };
        curve(&mut chart, name, &pts, color, name.starts_with("peak"))?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft, 13)
}
