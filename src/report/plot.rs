//! Error against run time on log-log axes: one curve per scheme and
//! microbuffer resolution (its Ω sweep), the Ω = 0 point, and the path tracer,
//! written as PNG and SVG. Text uses the embedded DejaVu Sans, so no system
//! font is needed.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use super::{ErrorPoint, Method};
use crate::cut::Scheme;
use crate::render::RenderError;

/// One curve: name and `(seconds, relative RMSE)` points, sorted by time.
type Curve = (String, Vec<(f64, f64)>);

fn curves(points: &[ErrorPoint], microbuffer: usize) -> Vec<Curve> {
    // Every (scheme, N) swept, the default N first, in the sweep's order.
    let mut keys: Vec<(Scheme, usize)> = Vec::new();
    for p in points {
        if let Method::PointBased {
            scheme,
            microbuffer: n,
            ..
        } = p.method
            && !keys.contains(&(scheme, n))
        {
            keys.push((scheme, n));
        }
    }
    keys.sort_by_key(|&(s, n)| (n != microbuffer, Scheme::ALL.iter().position(|&x| x == s)));
    let mut out: Vec<Curve> = Vec::new();
    let point_based = |keep: &dyn Fn(Scheme, f32, usize) -> bool| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = points
            .iter()
            .filter_map(|p| match p.method {
                Method::PointBased {
                    scheme,
                    max_solid_angle,
                    microbuffer: n,
                } if keep(scheme, max_solid_angle, n) => Some((p.total_s, p.rel_rmse)),
                _ => None,
            })
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    for (scheme, n) in keys {
        let v = point_based(&|s, max_solid_angle, m| s == scheme && m == n && max_solid_angle > 0.0);
        if !v.is_empty() {
            out.push((format!("pbgi {scheme} (Ω sweep, N {n})"), v));
        }
    }
    let zero = point_based(&|_, max_solid_angle, _| max_solid_angle == 0.0);
    if !zero.is_empty() {
        out.push(("pbgi Ω = 0 (every leaf splatted)".to_string(), zero));
    }
    let mut pt: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| matches!(p.method, Method::PathTracer { .. }))
        .map(|p| (p.total_s, p.rel_rmse))
        .collect();
    if !pt.is_empty() {
        pt.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.push(("path tracer (spp sweep)".to_string(), pt));
    }
    out
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
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let all = curves.iter().flat_map(|c| c.1.iter());
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(t, e) in all {
        if t > 0.0 && e > 0.0 {
            (t0, t1, e0, e1) = (t0.min(t), t1.max(t), e0.min(e), e1.max(e));
        }
    }
    if t0 > t1 {
        return Err("nothing to plot: no point with positive time and error".into());
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((t0 / 1.5..t1 * 1.5).log_scale(), (e0 / 1.3..e1 * 1.3).log_scale())
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
    for (i, (name, pts)) in curves.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = pts.iter().copied().filter(|&(t, e)| t > 0.0 && e > 0.0).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
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

/// Writes the error-against-time plot of `points` to `png` and `svg`: the
/// Ω sweep of each scheme at microbuffer resolution `microbuffer`, those at
/// the other resolutions swept, the Ω = 0 point and the path tracer's spp
/// sweep.
pub fn write_plots(
    points: &[ErrorPoint],
    microbuffer: usize,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), RenderError> {
    register_font();
    let curves = curves(points, microbuffer);
    let fail = |path: &Path, e: String| RenderError::Check(format!("{}: {e}", path.display()));
    let (w, h) = (900u32, 620u32);
    draw(SVGBackend::new(svg, (w, h)).into_drawing_area(), title, &curves).map_err(|e| fail(svg, e))?;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area(),
        title,
        &curves,
    )
    .map_err(|e| fail(png, e))?;
    image::save_buffer(png, &buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| fail(png, e.to_string()))?;
    Ok(())
}
