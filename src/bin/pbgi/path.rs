//! `pbgi render --camera-path`: every frame of a shot from one bake.

use std::path::{Path, PathBuf};
use std::time::Instant;

use pbgi::render::{Frame, RenderOptions};
use pbgi::scene::Scene;
use pbgi::scene::formats::read_camera_path;

use crate::args::Res;
use crate::farm::Frames;
use crate::progress::{progress_bar, tick};
use crate::{check_output, print_summary, write_image};

/// The file of frame `k`: `{}` in `pattern` becomes `k`, zero-padded to 4 digits.
pub fn frame_file(pattern: &Path, k: usize) -> PathBuf {
    PathBuf::from(pattern.to_string_lossy().replace("{}", &format!("{k:04}")))
}

/// The checked cameras of the path in `file` for `scene`'s camera; an
/// error names the file.
pub fn cameras(file: &Path, scene: &Scene) -> Res<Vec<pbgi::scene::Camera>> {
    let path = read_camera_path(file, &scene.camera)?;
    Ok(path
        .cameras(&scene.camera)
        .map_err(|e| format!("{}: {e}", file.display()))?)
}

/// The output pattern of a camera path: `-o`'s, which must hold `{}`, or
/// `SCENE-{}.png`.
pub fn pattern(output: Option<&Path>, scene: &str) -> Res<PathBuf> {
    match output {
        Some(p) if p.to_string_lossy().contains("{}") => Ok(p.to_path_buf()),
        Some(p) => Err(crate::exit::usage(format!(
            "-o {}: a camera path writes one image per frame; put {{}} where the frame number goes (frames/frame-{{}}.exr)",
            p.display()
        ))),
        None => Ok(PathBuf::from(format!("{scene}-{{}}.png"))),
    }
}

/// Renders the frames of the path in `file` (those of `frames`, or all)
/// with `frame`'s bake, writing each to `pattern`, and prints the first
/// frame's summary and the time per frame after it.
pub fn render_path(
    scene: &Scene,
    opts: &RenderOptions,
    frame: &mut Frame<'_>,
    (file, frames): (&Path, Option<Frames>),
    pattern: &Path,
    pool: &rayon::ThreadPool,
) -> Res<()> {
    let cameras = cameras(file, scene)?;
    let frames = match frames {
        Some(f) => f.within(cameras.len())?,
        None => Frames {
            first: 0,
            last: cameras.len().saturating_sub(1),
        },
    };
    for k in frames.first..=frames.last {
        check_output(&frame_file(pattern, k))?;
    }
    let n = frames.last + 1 - frames.first;
    let bar = progress_bar("frames", format!("rendering {n} frames of {}", scene.name));
    tick(&bar, 0, n);
    let mut seconds = Vec::with_capacity(n);
    let mut first = None;
    let mut written = Vec::new();
    for (k, camera) in cameras.into_iter().enumerate().skip(frames.first).take(n) {
        let clock = Instant::now();
        frame.set_camera(camera)?;
        let out = pool.install(|| frame.render(&|_, _| {}))?;
        let path = frame_file(pattern, k);
        write_image(&out.image, &path)?;
        seconds.push(clock.elapsed().as_secs_f64());
        written.push(format!(
            "frame {k:04}: {} receivers gathered, wrote {} (image digest {:016x})",
            out.receivers,
            path.display(),
            out.image.digest()
        ));
        first.get_or_insert(out);
        tick(&bar, k + 1 - frames.first, n);
    }
    bar.finish_and_clear();
    let first = first.expect("a camera path has frames");
    print_summary(scene, opts, &first, pool.current_num_threads());
    let later = &seconds[1..];
    let single = first.timings.pre + seconds[0];
    println!(
        "camera path: {} frame(s) from one bake (pre. {:.3} s, once); frame 0 {:.3} s{}",
        seconds.len(),
        first.timings.pre,
        seconds[0],
        if later.is_empty() {
            String::new()
        } else {
            let mean = later.iter().sum::<f64>() / later.len() as f64;
            format!(
                ", frames after the first {mean:.3} s each (mean of {}: {:.0} % of a single render's pre. + frame, {single:.3} s)",
                later.len(),
                100.0 * mean / single
            )
        }
    );
    for line in written {
        println!("{line}");
    }
    Ok(())
}
