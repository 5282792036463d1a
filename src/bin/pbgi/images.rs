//! Image files in and out: PNG (sRGB, 8 bits) and EXR (linear 32-bit
//! floats; the same pixels, the same bytes).

use std::path::Path;

use pbgi::render::Image;

use crate::args::Res;
use crate::exit;

/// Makes the folder an output file goes to, where missing: a farm task's
/// output goes to a fresh one.
pub(crate) fn make_folder_for(path: &Path) -> Res<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| exit::output(format!("{}: {e}", dir.display())))?;
    }
    Ok(())
}

/// Writes `img` to `path`, EXR or PNG by its extension ([`make_folder_for`]).
pub(crate) fn write_image(img: &Image, path: &Path) -> Res<()> {
    make_folder_for(path)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "exr" {
        use exr::prelude::*;
        let w = img.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p: glam::Vec3 = img.pixels[y * w + x];
            (p.x, p.y, p.z)
        });
        // Blocks compressed one after the other, so they are written in line
        // order: the parallel writer writes them as they finish, and the same
        // pixels would make a different file from run to run.
        exr::prelude::Image::from_channels((w, img.height as usize), channels)
            .write()
            .non_parallel()
            .to_file(path)
            .map_err(|e| exit::output(format!("{}: {e}", path.display())))?;
    } else {
        image::save_buffer(
            path,
            &img.to_srgb8(),
            img.width,
            img.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| exit::output(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// The first RGB(A) layer of the EXR file at `path`.
pub(crate) fn read_exr(path: &Path) -> Res<Image> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![glam::Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<glam::Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = glam::Vec3::new(r, g, b);
        },
    )
    .map_err(|e| exit::input(format!("{}: {e}", path.display())))?;
    let size = img.layer_data.size;
    let (_, pixels) = img.layer_data.channel_data.pixels;
    Ok(pbgi::render::Image {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels,
    })
}
