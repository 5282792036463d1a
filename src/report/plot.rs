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
        let style = color.stroke_width(2);
        let legend = move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style);
        if *method == Method::Denoised {
            chart
                .draw_series(DashedLineSeries::new(pts.clone(), 8, 4, style))
                .map_err(err)?
                .label(name.clone())
                .legend(legend);
        } else {
            chart
                .draw_series(LineSeries::new(pts.clone(), style))
                .map_err(err)?
                .label(name.clone())
                .legend(legend);
        }
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
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
