//! Texture images for every format: PNG and JPEG through `image`, EXR
//! through `exr`, each file decoded once per encoding however many
//! materials name it. A texture that cannot be read is a warning (the
//! material keeps its factors): a scene with a missing image still renders.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::scene::texture::{Encoding, Texture};

/// Where a texture's bytes are: a file, or bytes inside the scene file.
pub(super) enum ImageSource<'a> {
    /// A file on disk.
    File(&'a Path),
    /// Encoded bytes (a GLB chunk, a data URI), named for messages.
    Bytes { name: String, bytes: &'a [u8] },
}

/// Decoded textures by file (or name) and encoding.
#[derive(Default)]
pub(super) struct Images {
    decoded: HashMap<(PathBuf, bool), Result<Arc<Texture>, String>>,
}

impl Images {
    /// The texture at `source` under `encoding`; `Err` is the warning to give.
    pub fn get(&mut self, source: ImageSource, encoding: Encoding) -> Result<Arc<Texture>, String> {
        let key = match &source {
            ImageSource::File(p) => p.to_path_buf(),
            ImageSource::Bytes { name, .. } => PathBuf::from(name),
        };
        self.decoded
            .entry((key, encoding == Encoding::Srgb))
            .or_insert_with(|| decode(source, encoding).map(Arc::new))
            .clone()
    }
}

fn decode(source: ImageSource, encoding: Encoding) -> Result<Texture, String> {
    let (name, bytes) = match source {
        ImageSource::File(path) => {
            let name = path.display().to_string();
            let meta = std::fs::metadata(path).map_err(|e| format!("texture {name}: {e}"))?;
            if !meta.is_file() {
                return Err(format!("texture {name}: not a regular file"));
            }
            if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
                return exr_texture(path).map_err(|e| format!("texture {name}: {e}"));
            }
            let bytes = std::fs::read(path).map_err(|e| format!("texture {name}: {e}"))?;
            (name, std::borrow::Cow::Owned(bytes))
        }
        ImageSource::Bytes { name, bytes } => (name, std::borrow::Cow::Borrowed(bytes)),
    };
    let image = image::load_from_memory(&bytes).map_err(|e| format!("texture {name}: {e}"))?;
    let has_alpha = image.color().has_alpha();
    let (w, h) = (image.width(), image.height());
    let deep = image.color().bytes_per_pixel() / image.color().channel_count() > 1;
    let texture = if deep && encoding == Encoding::Linear {
        // 16-bit and float data keep their precision (height and normal maps).
        let texels = image.to_rgba32f().pixels().map(|p| p.0).collect();
        Texture::from_floats(name.clone(), w, h, texels, has_alpha)
    } else {
        let texels = image.to_rgba8().pixels().map(|p| p.0).collect();
        Texture::from_bytes(name.clone(), w, h, texels, encoding, has_alpha)
    };
    texture.map_err(|e| e.to_string())
}

/// An OpenEXR image's first RGBA layer, linear.
fn exr_texture(path: &Path) -> Result<Texture, String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0.0f32; 4]; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<[f32; 4]>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b, a];
        },
    )
    .map_err(|e| e.to_string())?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    let has_alpha = image.layer_data.channel_data.channels.3.is_some();
    Texture::from_floats(
        path.display().to_string(),
        size.width() as u32,
        size.height() as u32,
        texels,
        has_alpha,
    )
    .map_err(|e| e.to_string())
}
