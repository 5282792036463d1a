//! What the command line changes in a scene's own settings: the view
//! (`--resolution`, `--camera-*`, `--fov`), and the samples and bounces a
//! scene file asks for where `--spp` and `--bounces` are not given.

use crate::args::Res;
use crate::view::ViewArgs;

/// The camera as `--resolution`, `--camera-origin`, `--camera-target` and
/// `--fov` change it (the field of view stays on its axis); an unusable
/// camera is an error naming it.
pub fn set_view(scene: &mut pbgi::scene::Scene, v: &ViewArgs) -> Res<()> {
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

/// Bounces `pbgi render` takes for a file's unlimited `max_depth` (each is
/// a gather over every surfel): the ninth bounce off albedos of 0.5 carries
/// 0.5⁸ ≈ 0.4 % of the first's light.
const UNLIMITED_CAP: i32 = 8;

/// The samples per pixel and bounces a render takes: the command line's,
/// else the scene file's (`sample_count`, `max_depth`), else the command's
/// defaults (`None`); and a line saying which won where the file asked.
pub struct Won {
    pub spp: Option<u32>,
    pub bounces: Option<i32>,
    notes: Vec<String>,
}

impl Won {
    /// `bounded`: the point-based render, which takes a finite number of
    /// bounces (unlimited becomes [`UNLIMITED_CAP`]).
    pub fn choose(scene: &pbgi::scene::Scene, spp: Option<u32>, bounces: Option<i32>, bounded: bool) -> Won {
        let file = scene.file_settings;
        let mut notes = Vec::new();
        let spp = match (spp, file.sample_count) {
            (Some(n), Some(f)) => {
                notes.push(format!("--spp {n} over the file's sample_count {f}"));
                Some(n)
            }
            (None, Some(f)) => {
                notes.push(format!("{f} spp from the file's sample_count"));
                Some(f)
            }
            (n, None) => n,
        };
        let bounces = match (bounces, file.max_depth, file.bounces()) {
            (Some(b), Some(d), _) => {
                notes.push(format!("--bounces {b} over the file's max_depth {d}"));
                Some(b)
            }
            (None, Some(d), Some(b)) => {
                if b < 0 && bounded {
                    // Each bounce is a gather over every surfel: a cap, named.
                    notes.push(format!(
                        "{UNLIMITED_CAP} bounces for the file's max_depth {d} (unlimited; --bounces N for more)"
                    ));
                    Some(UNLIMITED_CAP)
                } else {
                    notes.push(format!("{b} bounce(s) from the file's max_depth {d}"));
                    Some(b)
                }
            }
            (b, ..) => b,
        };
        Won { spp, bounces, notes }
    }

    pub fn print(&self) {
        if !self.notes.is_empty() {
            println!("settings: {}", self.notes.join("; "));
        }
    }
}
