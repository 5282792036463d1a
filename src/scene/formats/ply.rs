//! PLY meshes (ASCII and binary, either endianness): vertices, optional
//! normals, faces as triangle fans.

use std::path::Path;

use glam::Vec3;

use super::common::{parse_err, regular_file, stem};
use crate::scene::{Mesh, SceneError};

#[derive(Clone, Copy, PartialEq)]
enum PlyFormat {
    Ascii,
    Little,
    Big,
}

fn ply_size(t: &str) -> Option<usize> {
    Some(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return None,
    })
}

struct PlyProp {
    name: String,
    ty: String,
    list: Option<String>,
}

struct PlyElement {
    name: String,
    count: usize,
    props: Vec<PlyProp>,
}

/// Reads a PLY mesh: vertices x, y, z (and nx, ny, nz), faces as index lists
/// (fan-triangulated); other properties and elements are skipped.
pub fn read_ply(path: &Path) -> Result<Mesh, SceneError> {
    regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| parse_err(path, 1, "no end_header"))?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| parse_err(path, 1, "header is not text"))?;
    let mut body = end + 10;
    while body < bytes.len() && (bytes[body] == b'\r' || bytes[body] == b'\n') {
        body += 1;
        if bytes[body - 1] == b'\n' {
            break;
        }
    }
    let header_lines = header.lines().count() + 1;
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    for (i, line) in header.lines().enumerate() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let bad = |m: &str| parse_err(path, i + 1, m.to_string());
        match w.first().copied() {
            Some("ply") | Some("comment") | Some("obj_info") | None => {}
            Some("format") => {
                format = Some(match w.get(1).copied() {
                    Some("ascii") => PlyFormat::Ascii,
                    Some("binary_little_endian") => PlyFormat::Little,
                    Some("binary_big_endian") => PlyFormat::Big,
                    _ => return Err(bad("unknown format")),
                })
            }
            Some("element") => {
                let count = w
                    .get(2)
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| bad("bad element count"))?;
                // Each element takes at least one byte: a count beyond the file is corrupt.
                if count > bytes.len() {
                    return Err(bad(&format!("element count {count} exceeds the file size")));
                }
                elements.push(PlyElement {
                    name: w.get(1).unwrap_or(&"").to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let p = if w.get(1) == Some(&"list") {
                    if w.len() < 5 || ply_size(w[2]).is_none() || ply_size(w[3]).is_none() {
                        return Err(bad("bad list property"));
                    }
                    PlyProp {
                        name: w[4].to_string(),
                        ty: w[3].to_string(),
                        list: Some(w[2].to_string()),
                    }
                } else {
                    if w.len() < 3 || ply_size(w[1]).is_none() {
                        return Err(bad("bad property"));
                    }
                    PlyProp {
                        name: w[2].to_string(),
                        ty: w[1].to_string(),
                        list: None,
                    }
                };
                e.props.push(p);
            }
            Some(other) => return Err(bad(&format!("unknown header keyword {other:?}"))),
        }
    }
    let format = format.ok_or_else(|| parse_err(path, 1, "no format line"))?;
    let mut reader = PlyReader {
        bytes: &bytes,
        pos: body,
        format,
        path,
        line: header_lines,
        tokens: Vec::new(),
    };
    let mut mesh = Mesh {
        name: stem(path),
        ..Mesh::default()
    };
    let mut normals = Vec::new();
    for e in &elements {
        for _ in 0..e.count {
            reader.start_row()?;
            let mut v = [0f64; 6];
            let mut has_normal = false;
            for p in &e.props {
                match &p.list {
                    Some(count_ty) => {
                        let n = reader.scalar(count_ty)?;
                        if !(0.0..=1e6).contains(&n) || n.fract() != 0.0 {
                            return Err(reader.error(&format!("bad list length {n}")));
                        }
                        let idx = (0..n as usize)
                            .map(|_| reader.scalar(&p.ty))
                            .collect::<Result<Vec<_>, _>>()?;
                        if e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index") {
                            let line = reader.line;
                            for k in 1..idx.len().saturating_sub(1) {
                                let t = [idx[0], idx[k], idx[k + 1]];
                                if t.iter().any(|&i| i < 0.0 || i.fract() != 0.0) {
                                    return Err(parse_err(path, line, "negative or fractional vertex index"));
                                }
                                mesh.triangles.push(t.map(|i| i as u32));
                            }
                        }
                    }
                    None => {
                        let x = reader.scalar(&p.ty)?;
                        if e.name == "vertex" {
                            let slot = ["x", "y", "z", "nx", "ny", "nz"]
                                .iter()
                                .position(|n| *n == p.name);
                            if let Some(s) = slot {
                                v[s] = x;
                                has_normal |= s >= 3;
                            }
                        }
                    }
                }
            }
            reader.end_row()?;
            if e.name == "vertex" {
                mesh.positions
                    .push(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32));
                if has_normal {
                    normals.push(Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32).normalize_or(Vec3::Z));
                }
            }
        }
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(parse_err(
            path,
            0,
            format!("face {t} refers to a vertex beyond the {n} given"),
        ));
    }
    if normals.len() == mesh.positions.len() && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

struct PlyReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: PlyFormat,
    path: &'a Path,
    line: usize,
    tokens: Vec<f64>,
}

impl PlyReader<'_> {
    fn error(&self, m: &str) -> SceneError {
        match self.format {
            PlyFormat::Ascii => parse_err(self.path, self.line, m.to_string()),
            _ => parse_err(self.path, self.line, format!("{m} (byte {})", self.pos)),
        }
    }

    fn start_row(&mut self) -> Result<(), SceneError> {
        if self.format != PlyFormat::Ascii {
            return Ok(());
        }
        loop {
            if self.pos >= self.bytes.len() {
                return Err(self.error("file ends early"));
            }
            let end = self.bytes[self.pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.bytes.len(), |i| self.pos + i);
            let text = String::from_utf8_lossy(&self.bytes[self.pos..end]).to_string();
            self.pos = end + 1;
            self.line += 1;
            if text.trim().is_empty() {
                continue;
            }
            let mut tokens = Vec::new();
            for t in text.split_whitespace().rev() {
                tokens.push(
                    t.parse::<f64>()
                        .map_err(|_| self.error(&format!("{t:?} is not a number")))?,
                );
            }
            self.tokens = tokens;
            return Ok(());
        }
    }

    fn end_row(&mut self) -> Result<(), SceneError> {
        Ok(())
    }

    fn scalar(&mut self, ty: &str) -> Result<f64, SceneError> {
        if self.format == PlyFormat::Ascii {
            return self
                .tokens
                .pop()
                .ok_or_else(|| self.error("too few values on the line"));
        }
        let size = ply_size(ty).ok_or_else(|| self.error("bad type"))?;
        if self.pos + size > self.bytes.len() {
            return Err(self.error("file ends early"));
        }
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(&self.bytes[self.pos..self.pos + size]);
        if self.format == PlyFormat::Big {
            b[..size].reverse();
        }
        self.pos += size;
        Ok(match ty {
            "char" | "int8" => b[0] as i8 as f64,
            "uchar" | "uint8" => b[0] as f64,
            "short" | "int16" => i16::from_le_bytes([b[0], b[1]]) as f64,
            "ushort" | "uint16" => u16::from_le_bytes([b[0], b[1]]) as f64,
            "int" | "int32" => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            "uint" | "uint32" => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            "float" | "float32" => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes(b),
        })
    }
}
