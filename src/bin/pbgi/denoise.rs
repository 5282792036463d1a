//! `--denoise`: the image through Intel OIDN, guided by its albedo and
//! normals, in a pbgi built with the `denoise` feature; a usage error in
//! one built without it, before any work.

use pbgi::render::{Frame, Image};
use rayon::ThreadPool;

use crate::args::Res;

/// Why `--denoise` cannot run in this build, if it cannot.
pub fn available() -> Res<()> {
    if cfg!(feature = "denoise") {
        Ok(())
    } else {
        Err(crate::exit::usage(
            "--denoise needs a pbgi built with the denoise feature: \
             export OIDN_DIR=$(scripts/oidn.sh); cargo build --release --features denoise",
        ))
    }
}

/// `image`, which `frame` rendered, denoised (its guides traced on
/// `pool`), and the summary's line on it.
#[cfg(feature = "denoise")]
pub fn denoise(frame: &Frame, image: &Image, pool: &ThreadPool) -> Res<(Image, String)> {
    let start = std::time::Instant::now();
    let guides = pool.install(|| frame.guides());
    let clean = pbgi::render::denoise(image, &guides)?;
    let said = format!(
        "denoised by Intel OIDN, guided by albedo and normals, in {:.3} s (the render's digest {:016x})",
        start.elapsed().as_secs_f64(),
        image.digest()
    );
    Ok((clean, said))
}

/// Without the feature: the usage error of [`available`].
#[cfg(not(feature = "denoise"))]
pub fn denoise(_: &Frame, image: &Image, _: &ThreadPool) -> Res<(Image, String)> {
    available().map(|()| (image.clone(), String::new()))
}
