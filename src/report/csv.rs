//! A sweep as CSV and back, so tables and plots can be redrawn without
//! rendering again. Fields holding a comma or a quote are quoted (RFC 4180):
//! scene names come from file names, labels from the settings.

use std::fmt::Write as _;

use super::error::ReportError;
use super::sweep::{ErrorPoint, Method};

/// `others_s` is the shading's time (its old name, kept so that older sweeps read back).
const HEADER: &str = "scene,method,label,spp,pre_s,trav_s,others_s,total_s,rel_rmse,floor";
/// The header before points kept their error's floor: read with floor 0.
const HEADER_WITHOUT_FLOOR: &str = "scene,method,label,spp,pre_s,trav_s,others_s,total_s,rel_rmse";

fn field(s: &str) -> String {
    // A line break would end the line: it becomes a space.
    let s = s.replace(['\n', '\r'], " ");
    if s.contains([',', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s
    }
}

/// The fields of one line, quotes undone; `None` if a quote is left open
/// or a quoted field runs into more text.
fn split(line: &str) -> Option<Vec<String>> {
    let mut fields = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        let mut f = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next()? {
                    '"' if chars.peek() == Some(&'"') => {
                        chars.next();
                        f.push('"');
                    }
                    '"' => break,
                    c => f.push(c),
                }
            }
            if !matches!(chars.peek(), None | Some(',')) {
                return None;
            }
        } else {
            while let Some(&c) = chars.peek() {
                if c == ',' {
                    break;
                }
                f.push(c);
                chars.next();
            }
        }
        fields.push(f);
        if chars.next().is_none() {
            return Some(fields);
        }
    }
}

/// The sweep as CSV: a header, then one line per image.
pub fn to_csv(scene: &str, points: &[ErrorPoint]) -> String {
    let mut s = format!("{HEADER}\n");
    for p in points {
        let method = match p.method {
            Method::PointBased => "pbgi",
            Method::PathTracer => "path-tracer",
            Method::Denoised => "denoised",
        };
        let _ = writeln!(
            s,
            "{},{method},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            field(scene),
            field(&p.label),
            p.spp,
            p.pre_s,
            p.trav_s,
            p.shading_s,
            p.total_s,
            p.rel_rmse,
            p.floor
        );
    }
    s
}

/// Reads back what [`to_csv`] wrote: the scene's name and the points. A
/// line that cannot be read is a [`ReportError::Csv`] naming it.
pub fn from_csv(text: &str) -> Result<(String, Vec<ErrorPoint>), ReportError> {
    let mut lines = text.lines().enumerate();
    let bad = |i: usize, what: &'static str, line: &str| ReportError::Csv {
        line: i + 1,
        what,
        text: line.to_string(),
    };
    let fields = match lines.next() {
        Some((_, h)) if h.trim() == HEADER => 10,
        Some((_, h)) if h.trim() == HEADER_WITHOUT_FLOOR => 9,
        h => {
            return Err(bad(
                0,
                "not the header of an error sweep's CSV",
                h.map_or("", |h| h.1),
            ));
        }
    };
    let mut scene = String::new();
    let mut points = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f = split(line).ok_or_else(|| bad(i, "a quote left open", line))?;
        if f.len() != fields {
            return Err(bad(
                i,
                if fields == 10 {
                    "expected 10 fields"
                } else {
                    "expected 9 fields"
                },
                line,
            ));
        }
        let num = |k: usize| {
            f[k].parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(i, "not a finite number", line))
        };
        let method = match f[1].as_str() {
            "pbgi" => Method::PointBased,
            "path-tracer" => Method::PathTracer,
            "denoised" => Method::Denoised,
            _ => return Err(bad(i, "unknown method", line)),
        };
        scene.clone_from(&f[0]);
        points.push(ErrorPoint {
            method,
            label: f[2].clone(),
            spp: f[3].parse().map_err(|_| bad(i, "bad spp", line))?,
            pre_s: num(4)?,
            trav_s: num(5)?,
            shading_s: num(6)?,
            total_s: num(7)?,
            rel_rmse: num(8)?,
            floor: if fields == 10 { num(9)? } else { 0.0 },
        });
    }
    Ok((scene, points))
}

/// The header of a list of images rendered outside the report.
const EXTERNAL_HEADER: &str = "label,spp,seconds,image";

/// One image rendered outside the report (`scripts/denoised.sh` writes
/// them): its curve, paths per pixel, wall-clock seconds and file.
#[derive(Clone, Debug, PartialEq)]
pub struct External {
    /// Its curve's label, e.g. "Mitsuba 3 + OIDN".
    pub label: String,
    /// Paths per pixel.
    pub spp: u32,
    /// Wall-clock seconds from scene file to denoised image.
    pub seconds: f64,
    /// The image, as written (relative paths are the caller's to resolve).
    pub image: String,
}

/// Reads a list of images rendered outside the report: the header
/// `label,spp,seconds,image`, then one line each. A line that cannot be
/// read is a [`ReportError::Csv`] naming it.
///
/// ```
/// use pbgi::report::external_points;
///
/// let text = "label,spp,seconds,image\n\"Mitsuba 3 + OIDN\",16,0.52,mitsuba-16.exr\n";
/// let e = external_points(text).unwrap();
/// assert_eq!((e[0].label.as_str(), e[0].spp, e[0].image.as_str()), ("Mitsuba 3 + OIDN", 16, "mitsuba-16.exr"));
/// assert!(external_points("label,spp,seconds,image\nx,16,-1,a.exr\n").is_err());
/// ```
pub fn external_points(text: &str) -> Result<Vec<External>, ReportError> {
    let mut lines = text.lines().enumerate();
    let bad = |i: usize, what: &'static str, line: &str| ReportError::Csv {
        line: i + 1,
        what,
        text: line.to_string(),
    };
    match lines.next() {
        Some((_, h)) if h.trim() == EXTERNAL_HEADER => {}
        h => {
            return Err(bad(
                0,
                "not the header label,spp,seconds,image",
                h.map_or("", |h| h.1),
            ));
        }
    }
    let mut out = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f = split(line).ok_or_else(|| bad(i, "a quote left open", line))?;
        let [label, spp, seconds, image] = f.as_slice() else {
            return Err(bad(i, "expected 4 fields", line));
        };
        out.push(External {
            label: label.clone(),
            spp: spp
                .parse()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| bad(i, "bad spp", line))?,
            seconds: seconds
                .parse::<f64>()
                .ok()
                .filter(|s| s.is_finite() && *s > 0.0)
                .ok_or_else(|| bad(i, "seconds not a positive number", line))?,
            image: image.clone(),
        });
    }
    Ok(out)
}
