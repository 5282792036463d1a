//! glTF bytes: the GLB container's chunks, the buffers (the GLB binary
//! chunk, base64 data URIs, `.bin` files beside the scene) and typed reads
//! of accessors, every length checked before it is used.

use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::buffer::Source;
use ::gltf::{Accessor, Document};
use glam::{Vec2, Vec3};

use super::super::common::{parse_err, regular_file};
use crate::scene::SceneError;

/// A GLB file's JSON chunk and its binary chunk, if any. Errors name the byte offset.
pub(super) fn split_glb<'b>(
    path: &Path,
    bytes: &'b [u8],
) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
    let bad = |at: usize, m: &str| parse_err(path, 0, format!("GLB byte {at}: {m}"));
    let word = |at: usize| -> Result<u32, SceneError> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad(at, &format!("file ends ({} bytes)", bytes.len())))
    };
    let version = word(4)?;
    if version != 2 {
        return Err(bad(4, &format!("version {version}, only 2 is read")));
    }
    let length = word(8)? as usize;
    if length > bytes.len() {
        return Err(bad(
            8,
            &format!("length {length} but the file has {} bytes", bytes.len()),
        ));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (size, kind) = (word(at)? as usize, word(at + 4)?);
        let body = at + 8;
        let end = body
            .checked_add(size)
            .filter(|&e| e <= length)
            .ok_or_else(|| bad(at, &format!("chunk of {size} bytes runs past the end ({length})")))?;
        chunks.push((at, kind, &bytes[body..end]));
        // Chunks are 4-byte aligned.
        at = end.next_multiple_of(4);
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(_, JSON, json)) => Ok((json, chunks.get(1).filter(|c| c.1 == BIN).map(|c| c.2))),
        Some(&(at, _, _)) => Err(bad(at, "the first chunk is not JSON")),
        None => Err(bad(12, "no JSON chunk")),
    }
}

/// Every buffer's bytes, in order: the GLB binary chunk, a base64 data URI,
/// or a file relative to the scene file.
pub(super) fn load_buffers(
    path: &Path,
    doc: &Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    doc.buffers()
        .map(|b| {
            let what = format!("buffer {}", b.index());
            let data = match b.source() {
                Source::Bin => blob
                    .ok_or_else(|| {
                        parse_err(
                            path,
                            0,
                            format!("{what} is the GLB binary chunk, which is missing"),
                        )
                    })?
                    .to_vec(),
                Source::Uri(uri) if uri.starts_with("data:") => {
                    let payload = uri.split_once(";base64,").map(|(_, p)| p).ok_or_else(|| {
                        parse_err(path, 0, format!("{what}: a data URI that is not base64"))
                    })?;
                    base64(payload).map_err(|at| {
                        parse_err(
                            path,
                            0,
                            format!("{what}: bad base64 at character {at} of the data URI"),
                        )
                    })?
                }
                Source::Uri(uri) if uri.contains("://") => {
                    return Err(SceneError::Unsupported {
                        path: path.to_path_buf(),
                        line: 0,
                        what: format!("{what}: URI {uri:?} (only data URIs and files beside the scene)"),
                    });
                }
                Source::Uri(uri) => {
                    let file = dir.join(percent_decode(uri));
                    let io = |message: String| SceneError::Io {
                        path: file.clone(),
                        message: format!("{what} of {}: {message}", path.display()),
                    };
                    regular_file(&file).map_err(|e| match e {
                        SceneError::Io { message, .. } => io(message),
                        e => e,
                    })?;
                    std::fs::read(&file).map_err(|e| io(e.to_string()))?
                }
            };
            if data.len() < b.length() {
                return Err(parse_err(
                    path,
                    0,
                    format!("{what} declares {} bytes but has {}", b.length(), data.len()),
                ));
            }
            Ok(data)
        })
        .collect()
}

/// Standard base64 (padding optional); the error is the offending character's position.
pub(super) fn base64(s: &str) -> Result<Vec<u8>, usize> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0);
    for (i, c) in s.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' if s[i..].bytes().all(|c| c == b'=') => break,
            _ => return Err(i),
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Ok(out)
}

/// `%20` and friends in a relative URI.
pub(super) fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .and_then(|h| u8::from_str_radix(std::str::from_utf8(h).ok()?, 16).ok());
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Typed reads of accessors; errors name the file and the item (`what`).
pub(super) struct Buffers<'a> {
    pub path: &'a Path,
    pub data: Vec<Vec<u8>>,
}

impl Buffers<'_> {
    /// The accessor's elements as byte slices of `size` bytes, bounds checked.
    fn elements<'s>(&'s self, what: &str, a: &Accessor) -> Result<Vec<&'s [u8]>, SceneError> {
        let bad = |m: String| parse_err(self.path, 0, format!("{what}: accessor {} {m}", a.index()));
        if a.sparse().is_some() {
            return Err(SceneError::Unsupported {
                path: self.path.to_path_buf(),
                line: 0,
                what: format!("{what}: sparse accessor {}", a.index()),
            });
        }
        let view = a.view().ok_or_else(|| bad("has no buffer view".into()))?;
        let buffer = &self.data[view.buffer().index()];
        let size = a.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(bad(format!(
                "has stride {stride}, less than its element size {size}"
            )));
        }
        let bytes = view
            .offset()
            .checked_add(view.length())
            .and_then(|end| buffer.get(view.offset()..end))
            .ok_or_else(|| {
                bad(format!(
                    "reads buffer view {} (bytes {}..+{}) beyond buffer {} ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    buffer.len()
                ))
            })?;
        let count = a.count();
        if count == 0 {
            return Ok(Vec::new());
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|s| s.checked_add(a.offset()))
            .and_then(|s| s.checked_add(size));
        match end {
            Some(end) if end <= bytes.len() => Ok((0..count)
                .map(|i| &bytes[a.offset() + i * stride..][..size])
                .collect()),
            _ => Err(bad(format!(
                "of {count} elements runs past buffer view {} ({} bytes)",
                view.index(),
                bytes.len()
            ))),
        }
    }

    /// A `VEC3` float accessor (positions, normals).
    pub fn vec3(&self, what: &str, a: &Accessor) -> Result<Vec<Vec3>, SceneError> {
        if a.dimensions() != Dimensions::Vec3 || a.data_type() != DataType::F32 || a.normalized() {
            return Err(parse_err(
                self.path,
                0,
                format!(
                    "{what}: accessor {} is {:?} {:?}, expected VEC3 float",
                    a.index(),
                    a.dimensions(),
                    a.data_type()
                ),
            ));
        }
        let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        Ok(self
            .elements(what, a)?
            .into_iter()
            .map(|e| Vec3::new(f(&e[0..4]), f(&e[4..8]), f(&e[8..12])))
            .collect())
    }

    /// A `VEC2` accessor of floats or normalized unsigned bytes or shorts
    /// (texture coordinates).
    pub fn vec2(&self, what: &str, a: &Accessor) -> Result<Vec<Vec2>, SceneError> {
        let read: fn(&[u8]) -> Vec2 = match (a.dimensions(), a.data_type(), a.normalized()) {
            (Dimensions::Vec2, DataType::F32, _) => |b| {
                let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                Vec2::new(f(&b[0..4]), f(&b[4..8]))
            },
            (Dimensions::Vec2, DataType::U8, true) => |b| Vec2::new(b[0] as f32, b[1] as f32) / 255.0,
            (Dimensions::Vec2, DataType::U16, true) => |b| {
                let s = |b: &[u8]| u16::from_le_bytes([b[0], b[1]]) as f32;
                Vec2::new(s(&b[0..2]), s(&b[2..4])) / 65535.0
            },
            (d, t, _) => {
                return Err(parse_err(
                    self.path,
                    0,
                    format!(
                        "{what}: accessor {} is {d:?} {t:?}, expected VEC2 float or normalized unsigned",
                        a.index()
                    ),
                ));
            }
        };
        Ok(self.elements(what, a)?.into_iter().map(read).collect())
    }

    /// The bytes of a buffer view (an embedded image), `None` past its buffer's end.
    pub fn view(&self, view: &::gltf::buffer::View) -> Option<&[u8]> {
        let end = view.offset().checked_add(view.length())?;
        self.data.get(view.buffer().index())?.get(view.offset()..end)
    }

    /// A `SCALAR` unsigned-integer accessor (indices).
    pub fn indices(&self, what: &str, a: &Accessor) -> Result<Vec<u32>, SceneError> {
        let read: fn(&[u8]) -> u32 = match (a.dimensions(), a.data_type()) {
            (Dimensions::Scalar, DataType::U8) => |b| b[0] as u32,
            (Dimensions::Scalar, DataType::U16) => |b| u16::from_le_bytes([b[0], b[1]]) as u32,
            (Dimensions::Scalar, DataType::U32) => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            (d, t) => {
                return Err(parse_err(
                    self.path,
                    0,
                    format!(
                        "{what}: accessor {} is {d:?} {t:?}, expected SCALAR unsigned",
                        a.index()
                    ),
                ));
            }
        };
        Ok(self.elements(what, a)?.into_iter().map(read).collect())
    }
}
