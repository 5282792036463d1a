//! What the command line changes in a scene's own settings: the view
//! (`--resolution`, `--camera-*`, `--fov`), and the samples and bounces a
//! scene file asks for where `--spp` and `--bounces` are not given.

use pbgi::render::{Flags, RenderOptions, Resolved};
use pbgi::scene::Scene;

use crate::args::{Res, Settings};
use crate::view::ViewArgs;

/// The camera as `--resolution`, `--camera-origin`, `--camera-target` and
/// `--fov` change it (the field of view stays on its axis); an unusable
/// camera is an error naming it.
pub fn set_view(scene: &mut Scene, v: &ViewArgs) -> Res<()> {
    let c = &mut scene.camera;
    if let Some((w, h)) = v.resolution {
        (c.width, c.height) = (w, h);
    }
    if let Some(p) = v.camera_origin {
        c.origin = glam::Vec3::from(p);
    }
    if let Some(p) = v.camera_target {
        c.target = glam::Vec3::from(p);
    }
    if let Some(f) = v.fov {
        c.fov_degrees = f;
    }
    scene.validate()?;
    Ok(())
}

/// A subcommand's render settings for `scene` (named `arg` on the command
/// line): `base` resolved by [`RenderOptions::resolve`], the flags over
/// the scene file over the defaults, and which won where the file asked
/// ([`print_notes`]).
pub fn resolve(scene: &Scene, arg: &str, base: RenderOptions, s: &Settings, spp: Option<u32>) -> Resolved {
    let flags = Flags {
        spp,
        bounces: s.bounces,
        density: s.density,
        surfel_budget: s.surfels,
        named: pbgi::scene::catalogue::is_named(arg),
    };
    base.resolve(scene, &flags)
}

/// `settings: …`, where the scene file asked for something.
pub fn print_notes<'a>(notes: impl IntoIterator<Item = &'a String>) {
    let notes: Vec<&str> = notes.into_iter().map(String::as_str).collect();
    if !notes.is_empty() {
        println!("settings: {}", notes.join("; "));
    }
}
