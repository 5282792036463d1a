//! `pbgi report --camera-path`: each frame's error and the flicker of a shot
//! (`pbgi::report::flicker`), for point-based GI rendered from one bake, the
//! path tracer, and denoised frames rendered beforehand.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use pbgi::render::{Frame, Image, ReferenceOptions, render_reference};
use pbgi::report::{Flicker, OIDN_SUFFIX, emitter_mask, external_points, flicker};
use pbgi::scene::Scene;

use crate::args::{ReportArgs, Res};
use crate::path::frame_file;
use crate::{load_scene, read_exr, thread_pool, write_image};

/// Camera samples per pixel of the point-based rows by default.
const SPP: [u32; 3] = [4, 16, 64];
/// Paths per pixel of the path tracer's rows by default.
const PATH_TRACER_SPP: [u32; 2] = [16, 256];

/// One row: what rendered the frames, their flicker and seconds per frame.
struct Row {
    label: String,
    spp: u32,
    flicker: Flicker,
    seconds: f64,
}

pub fn cmd_flicker(a: &ReportArgs, path_file: &Path) -> Res<()> {
    if a.denoise {
        crate::denoise::available()?;
    }
    let mut scene = load_scene(&a.scene)?;
    crate::overrides::set_view(&mut scene, &a.view)?;
    let cameras = crate::path::cameras(path_file, &scene)?;
    let pool = thread_pool(a.threads)?;
    let opts = crate::overrides::resolve(&scene, &a.scene, a.settings.options(1)?, &a.settings, None).options;
    let framed = |k: usize| Scene {
        camera: cameras[k],
        ..scene.clone()
    };
    let n = cameras.len();
    let masks: Vec<Vec<bool>> = (0..n).map(|k| emitter_mask(&framed(k))).collect();
    let dir = a
        .reference_dir
        .clone()
        .unwrap_or_else(|| a.out.join("references"));
    std::fs::create_dir_all(&dir).map_err(|e| crate::exit::output(format!("{}: {e}", dir.display())))?;
    // The references: the path tracer at --reference-spp, a new seed per frame.
    let mut references = Vec::with_capacity(n);
    for k in 0..n {
        let file = frame_file(&dir.join("reference-{}.exr"), k);
        if !file.exists() {
            eprintln!(
                "path tracing the reference of frame {k} ({} spp) to {}",
                a.reference_spp,
                file.display()
            );
            let o = ReferenceOptions {
                spp: a.reference_spp,
                bounces: opts.bounces as i32,
                seed: 1_000 + k as u64,
                ..ReferenceOptions::default()
            };
            let out = pool.install(|| render_reference(&framed(k), &o, &|_, _| {}))?;
            write_image(&out.image, &file)?;
        }
        references.push(read_exr(&file)?);
    }
    let measure = |label: String, spp: u32, frames: Vec<Image>, seconds: f64| -> Res<Row> {
        let flicker =
            flicker(&frames, &references, &masks).map_err(|e| format!("{label}, {spp} spp: {e}"))?;
        Ok(Row {
            label,
            spp,
            flicker,
            seconds,
        })
    };
    let mut rows = Vec::new();
    for &spp in a.spp.as_deref().unwrap_or(&SPP) {
        let o = pbgi::render::RenderOptions { spp, ..opts };
        let clock = Instant::now();
        let mut frame = pool.install(|| Frame::prepare(&scene, &o))?;
        let (mut frames, mut clean) = (Vec::with_capacity(n), Vec::new());
        // The denoiser's own seconds (guides and filter), apart.
        let mut denoising = 0.0;
        for camera in &cameras {
            frame.set_camera(*camera)?;
            let image = pool.install(|| frame.render(&|_, _| {}))?.image;
            if a.denoise {
                let start = Instant::now();
                clean.push(crate::denoise::denoise(&frame, &image, &pool)?.0);
                denoising += start.elapsed().as_secs_f64();
            }
            frames.push(image);
        }
        let seconds = (clock.elapsed().as_secs_f64() - denoising) / n as f64;
        eprintln!("point-based GI, {spp} spp: {seconds:.2} s per frame");
        rows.push(measure("pbgi".into(), spp, frames, seconds)?);
        if a.denoise {
            let with = seconds + denoising / n as f64;
            rows.push(measure(format!("pbgi{OIDN_SUFFIX}"), spp, clean, with)?);
        }
    }
    for &spp in a.path_tracer_spp.as_deref().unwrap_or(&PATH_TRACER_SPP) {
        let clock = Instant::now();
        let mut frames = Vec::with_capacity(n);
        for k in 0..n {
            let o = ReferenceOptions {
                spp,
                bounces: opts.bounces as i32,
                seed: 1 + k as u64,
                ..ReferenceOptions::default()
            };
            frames.push(
                pool.install(|| render_reference(&framed(k), &o, &|_, _| {}))?
                    .image,
            );
        }
        let seconds = clock.elapsed().as_secs_f64() / n as f64;
        eprintln!("path tracer, {spp} spp: {seconds:.2} s per frame");
        rows.push(measure("path tracer (pbgi)".into(), spp, frames, seconds)?);
    }
    // Frames rendered beforehand: `label,spp,seconds,image`, the image a
    // pattern with `{}` for the frame number, seconds per frame.
    for csv in &a.denoised {
        let text = std::fs::read_to_string(csv)
            .map_err(|e| crate::exit::input(format!("{}: {e}", csv.display())))?;
        let base = csv.parent().unwrap_or(Path::new("."));
        for e in external_points(&text).map_err(|e| crate::exit::input(format!("{}: {e}", csv.display())))? {
            if !e.image.contains("{}") {
                return Err(crate::exit::input(format!(
                    "{}: {}: a frame pattern needs {{}} for the frame number",
                    csv.display(),
                    e.image
                )));
            }
            let frames = (0..n)
                .map(|k| read_exr(&frame_file(&base.join(&e.image), k)))
                .collect::<Res<Vec<_>>>()?;
            rows.push(measure(e.label, e.spp, frames, e.seconds)?);
        }
    }
    let table = markdown(&scene.name, n, a.reference_spp, &rows);
    print!("{table}");
    std::fs::create_dir_all(&a.out).map_err(|e| crate::exit::output(format!("{}: {e}", a.out.display())))?;
    let md = a.out.join("flicker.md");
    std::fs::write(&md, &table).map_err(|e| crate::exit::output(format!("{}: {e}", md.display())))?;
    let csv = a.out.join("flicker.csv");
    let mut text = String::from("label,spp,frame_error,flicker,seconds_per_frame\n");
    for r in &rows {
        let _ = writeln!(
            text,
            "{},{},{:.6},{:.6},{:.4}",
            r.label,
            r.spp,
            r.flicker.frame_error(),
            r.flicker.flicker,
            r.seconds
        );
    }
    std::fs::write(&csv, text).map_err(|e| crate::exit::output(format!("{}: {e}", csv.display())))?;
    println!("wrote {}, {}", md.display(), csv.display());
    Ok(())
}

fn markdown(scene: &str, frames: usize, reference_spp: u32, rows: &[Row]) -> String {
    let mut s = format!(
        "{scene}, {frames} frames against the path tracer at {reference_spp} spp (a new seed per frame)\n\n\
         | renderer | spp | per-frame error | flicker | flicker / error | s per frame |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n"
    );
    for r in rows {
        let (e, f) = (r.flicker.frame_error(), r.flicker.flicker);
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} % | {:.2} % | {:.2} | {:.2} |",
            r.label,
            r.spp,
            100.0 * e,
            100.0 * f,
            f / e,
            r.seconds
        );
    }
    s
}
