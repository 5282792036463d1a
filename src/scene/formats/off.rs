//! OFF meshes (Geomview's Object File Format, as mesh repositories and
//! CGAL write them): `OFF` (or `COFF`, `NOFF`, `CNOFF`: colours and normals
//! after the coordinates are read past), the counts, the vertices, then
//! polygons fan-triangulated. `#` starts a comment.

use std::path::Path;

use glam::Vec3;

use super::common::{parse_err, read_text, stem};
use crate::scene::{Mesh, SceneError};

/// Reads an OFF file into one mesh. Polygons of fewer than three vertices
/// are left out (counted in the returned warnings).
pub fn read_off(path: &Path) -> Result<(Mesh, Vec<String>), SceneError> {
    let text = read_text(path)?;
    // Tokens with their line numbers, comments dropped.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("")))
        .filter(|(_, l)| !l.trim().is_empty());
    let (line, first) = lines.next().ok_or_else(|| parse_err(path, 1, "empty file"))?;
    let mut words = first.split_whitespace();
    let magic = words.next().unwrap_or("");
    if !matches!(magic, "OFF" | "COFF" | "NOFF" | "CNOFF" | "NCOFF") {
        return Err(parse_err(path, line, format!("expected OFF, found {magic:?}")));
    }
    // The counts may follow the keyword on its line.
    let rest: Vec<&str> = words.collect();
    let (line, counts) = if rest.is_empty() {
        let (l, c) = lines
            .next()
            .ok_or_else(|| parse_err(path, line, "no vertex and face counts"))?;
        (l, c.split_whitespace().collect::<Vec<_>>())
    } else {
        (line, rest)
    };
    let count = |k: usize, what: &str| -> Result<usize, SceneError> {
        counts
            .get(k)
            .and_then(|t| t.parse::<usize>().ok())
            .ok_or_else(|| parse_err(path, line, format!("bad {what} count")))
    };
    let (nv, nf) = (count(0, "vertex")?, count(1, "face")?);
    // Each vertex and face takes a line: counts beyond the file are refused
    // before anything is allocated for them.
    let remaining = text.lines().count().saturating_sub(line);
    if nv.saturating_add(nf) > remaining {
        return Err(parse_err(
            path,
            line,
            format!("{nv} vertices and {nf} faces announced, {remaining} lines follow"),
        ));
    }
    let mut mesh = Mesh {
        name: stem(path),
        ..Mesh::default()
    };
    mesh.positions.reserve(nv);
    for _ in 0..nv {
        let (line, l) = lines
            .next()
            .ok_or_else(|| parse_err(path, line, "fewer vertices than announced"))?;
        let xyz: Vec<f32> = l
            .split_whitespace()
            .take(3)
            .filter_map(|t| t.parse().ok())
            .collect();
        match xyz[..] {
            [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
                mesh.positions.push(Vec3::new(x, y, z))
            }
            _ => return Err(parse_err(path, line, format!("bad vertex {l:?}"))),
        }
    }
    let mut degenerate = (0usize, 0usize);
    for _ in 0..nf {
        let (line, l) = lines
            .next()
            .ok_or_else(|| parse_err(path, line, "fewer faces than announced"))?;
        let mut w = l.split_whitespace();
        let n: usize = w
            .next()
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| parse_err(path, line, format!("bad face {l:?}")))?;
        let idx: Vec<u32> = w
            .take(n)
            .map(|t| match t.parse::<u32>() {
                Ok(k) if (k as usize) < nv => Ok(k),
                _ => Err(parse_err(
                    path,
                    line,
                    format!("face index {t:?} out of range ({nv} vertices)"),
                )),
            })
            .collect::<Result<_, _>>()?;
        if idx.len() < n {
            return Err(parse_err(
                path,
                line,
                format!("face of {n} vertices lists {}", idx.len()),
            ));
        }
        if n < 3 {
            if degenerate.0 == 0 {
                degenerate.1 = line;
            }
            degenerate.0 += 1;
            continue;
        }
        for k in 1..n - 1 {
            mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
    let mut warnings = Vec::new();
    if degenerate.0 > 0 {
        warnings.push(format!(
            "{}: {} face(s) with fewer than three vertices left out (the first at line {})",
            path.display(),
            degenerate.0,
            degenerate.1
        ));
    }
    Ok((mesh, warnings))
}
