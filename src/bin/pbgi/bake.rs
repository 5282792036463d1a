//! `pbgi bake`: the surfels and tree written to a file, and read back for
//! `pbgi render --tree`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use pbgi::TreeFile;
use pbgi::render::bake_tree_with_progress;

use crate::args::{BakeArgs, Res, bake_options};
use crate::overrides::{print_notes, resolve};
use crate::{StageBars, load_lit_scene, thread_pool};

/// A tree file, read and checked, with the seconds that took.
pub fn load_tree(path: &Path) -> Res<(TreeFile, &Path, f64)> {
    let t0 = Instant::now();
    let file =
        std::fs::File::open(path).map_err(|e| crate::exit::input(format!("{}: {e}", path.display())))?;
    // A device or a pipe could be endless.
    if !file.metadata().is_ok_and(|m| m.is_file()) {
        return Err(crate::exit::input(format!(
            "{}: not a regular file",
            path.display()
        )));
    }
    drop(file);
    // Mapped: a compact tree is used where it lies in the file.
    let tree = TreeFile::open(path).map_err(|e| crate::exit::input(format!("{}: {e}", path.display())))?;
    Ok((tree, path, t0.elapsed().as_secs_f64()))
}

pub fn cmd_bake(a: &BakeArgs) -> Res<()> {
    let scene = load_lit_scene(&a.scene, &a.environment)?;
    // The file's max_depth as `pbgi render` takes it: the tree serves that
    // render (its camera samples do not matter to the bake).
    let resolved = resolve(&scene, &a.scene, bake_options(a)?, &a.settings, None);
    let opts = resolved.options;
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.pbgi", scene.name)));
    let pool = thread_pool(a.threads)?;
    let t0 = Instant::now();
    let stages = StageBars::new(&scene.name);
    let file = pool.install(|| bake_tree_with_progress(&scene, &opts, &|s, d, n| stages.report(s, d, n)));
    stages.finish();
    let file = file?;
    let seconds = t0.elapsed().as_secs_f64();
    crate::images::make_folder_for(&out_path)?;
    // Under a new name, then renamed: a render mapping the old file keeps it.
    file.write_to(&out_path)
        .map_err(|e| crate::exit::output(format!("{}: {e}", out_path.display())))?;
    let bytes = std::fs::metadata(&out_path).map_or(0, |m| m.len());
    let b = file.bake();
    println!(
        "pbgi bake: {} ({} triangles), {} bounce(s){}, density {}{}",
        scene.name,
        scene.triangle_count(),
        b.bounces,
        if b.ao { ", ambient occlusion" } else { "" },
        b.density,
        if b.gathered {
            format!(
                ", gathered at Ω {} and microbuffer {}",
                b.max_solid_angle, b.microbuffer
            )
        } else {
            String::new()
        }
    );
    print_notes(&resolved.bounces_note);
    println!(
        "{} surfels, {} nodes, depth {}, {:.1} MB, in {seconds:.3} s on {} thread(s)",
        file.cloud().len(),
        file.tree().len(),
        file.tree().depth(),
        bytes as f64 / 1e6,
        pool.current_num_threads()
    );
    println!("wrote {} (scene hash {:016x})", out_path.display(), b.scene);
    Ok(())
}
