//! The settings a render takes, resolved in one place: what the caller
//! gives (the command line's flags), over what the scene file asks for,
//! over the caller's base options (the defaults). Every subcommand of the
//! CLI resolves through [`RenderOptions::resolve`], so a report measures
//! the render `pbgi render` would make.

use super::options::{DEFAULT_SURFEL_BUDGET, RenderOptions};
use crate::scene::{FileSettings, Scene};

/// Bounces a point-based render takes for a scene file's unlimited
/// `max_depth` (each is a gather over every surfel): the ninth bounce off
/// albedos of 0.5 carries 0.5⁸ ≈ 0.4 % of the first's light.
pub const UNLIMITED_BOUNCES: u32 = 8;

/// What the caller sets over a scene's own settings; `None`: not given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Flags {
    /// Camera samples per pixel (over the file's `sample_count`).
    pub spp: Option<u32>,
    /// Indirect bounces (over the file's `max_depth`).
    pub bounces: Option<u32>,
    /// Surfels per unit area.
    pub density: Option<f32>,
    /// About this many surfels whatever the scene's units.
    pub surfel_budget: Option<u32>,
    /// The scene came by its name (built in, or fetched), not as a file:
    /// it keeps the base options' density where neither `density` nor
    /// `surfel_budget` is given, so its images stay as they were; a file
    /// gets [`DEFAULT_SURFEL_BUDGET`].
    pub named: bool,
}

/// Resolved settings, and for each the scene file asked for, which won.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    /// What the render takes.
    pub options: RenderOptions,
    /// Where the file asked for camera samples: `"--spp 8 over the file's
    /// sample_count 4"` or `"4 spp from the file's sample_count"`.
    pub spp_note: Option<String>,
    /// Where the file asked for bounces, the same.
    pub bounces_note: Option<String>,
}

impl Resolved {
    /// Both notes, those there are.
    pub fn notes(&self) -> Vec<String> {
        self.spp_note.iter().chain(&self.bounces_note).cloned().collect()
    }
}

/// Samples per pixel: the flag, else the file's `sample_count`, else
/// `None` (the caller's default), with a note where the file asked.
pub fn file_spp(file: FileSettings, spp: Option<u32>) -> (Option<u32>, Option<String>) {
    match (spp, file.sample_count) {
        (Some(n), Some(f)) => (
            Some(n),
            Some(format!("--spp {n} over the file's sample_count {f}")),
        ),
        (None, Some(f)) => (Some(f), Some(format!("{f} spp from the file's sample_count"))),
        (n, None) => (n, None),
    }
}

/// Indirect bounces: the flag, else the file's `max_depth`, else `None`
/// (the caller's default), with a note where the file asked. `bounded`:
/// an unlimited `max_depth` becomes [`UNLIMITED_BOUNCES`] (the point-based
/// render); the path tracer keeps it (−1).
pub fn file_bounces(
    file: FileSettings,
    bounces: Option<i32>,
    bounded: bool,
) -> (Option<i32>, Option<String>) {
    match (bounces, file.max_depth, file.bounces()) {
        (Some(b), Some(d), _) => (
            Some(b),
            Some(format!("--bounces {b} over the file's max_depth {d}")),
        ),
        (None, Some(d), Some(b)) if b < 0 && bounded => (
            Some(UNLIMITED_BOUNCES as i32),
            Some(format!(
                "{UNLIMITED_BOUNCES} bounces for the file's max_depth {d} (unlimited; --bounces N for more)"
            )),
        ),
        (None, Some(d), Some(b)) => (
            Some(b),
            Some(format!("{b} bounce(s) from the file's max_depth {d}")),
        ),
        (b, ..) => (b, None),
    }
}

impl RenderOptions {
    /// The settings a render of `scene` takes, each on its own, in this
    /// order:
    ///
    /// 1. `flags`, where given;
    /// 2. else the scene file's: `sample_count` for the camera samples,
    ///    `max_depth` for the bounces (unlimited: [`UNLIMITED_BOUNCES`]);
    /// 3. else `self`'s.
    ///
    /// The surfels: `flags.density` or `flags.surfel_budget` where given,
    /// else a file gets [`DEFAULT_SURFEL_BUDGET`] and a named scene
    /// `self`'s density or budget.
    ///
    /// ```
    /// use pbgi::render::{Flags, RenderOptions};
    /// let mut scene = pbgi::scene::builtin::cornell_box();
    /// scene.file_settings.sample_count = Some(16);
    /// let file = RenderOptions::default().resolve(&scene, &Flags::default());
    /// assert_eq!(file.options.spp, 16);
    /// let flag = RenderOptions::default().resolve(&scene, &Flags { spp: Some(2), ..Flags::default() });
    /// assert_eq!(flag.options.spp, 2);
    /// assert_eq!(flag.notes(), ["--spp 2 over the file's sample_count 16"]);
    /// ```
    pub fn resolve(&self, scene: &Scene, flags: &Flags) -> Resolved {
        let bounces = flags.bounces.map(|b| b.min(i32::MAX as u32) as i32);
        let (spp, spp_note) = file_spp(scene.file_settings, flags.spp);
        let (bounces, bounces_note) = file_bounces(scene.file_settings, bounces, true);
        let (density, surfel_budget) = match (flags.density, flags.surfel_budget) {
            (None, None) if !flags.named => (self.density, Some(DEFAULT_SURFEL_BUDGET)),
            (None, None) => (self.density, self.surfel_budget),
            (density, budget) => (density.unwrap_or(self.density), budget),
        };
        Resolved {
            options: RenderOptions {
                spp: spp.unwrap_or(self.spp),
                bounces: bounces.map_or(self.bounces, |b| b.max(0) as u32),
                density,
                surfel_budget,
                ..*self
            },
            spp_note,
            bounces_note,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::cornell_box;

    fn scene(sample_count: Option<u32>, max_depth: Option<i32>) -> Scene {
        let mut s = cornell_box();
        s.file_settings = FileSettings {
            max_depth,
            sample_count,
        };
        s
    }

    /// Each setting on its own: the flag over the file over the base.
    #[test]
    fn flags_win_over_the_file_and_the_file_over_the_base() {
        let base = RenderOptions {
            spp: 3,
            bounces: 2,
            ..RenderOptions::default()
        };
        let none = base.resolve(&scene(None, None), &Flags::default());
        assert_eq!((none.options.spp, none.options.bounces), (3, 2));
        assert!(none.notes().is_empty());
        let file = base.resolve(&scene(Some(16), Some(5)), &Flags::default());
        assert_eq!((file.options.spp, file.options.bounces), (16, 3));
        assert_eq!(
            file.notes(),
            [
                "16 spp from the file's sample_count",
                "3 bounce(s) from the file's max_depth 5"
            ]
        );
        let flags = Flags {
            spp: Some(1),
            ..Flags::default()
        };
        let mixed = base.resolve(&scene(Some(16), Some(5)), &flags);
        assert_eq!((mixed.options.spp, mixed.options.bounces), (1, 3));
        let both = base.resolve(
            &scene(Some(16), Some(5)),
            &Flags {
                bounces: Some(0),
                ..flags
            },
        );
        assert_eq!((both.options.spp, both.options.bounces), (1, 0));
        assert_eq!(
            both.bounces_note.as_deref(),
            Some("--bounces 0 over the file's max_depth 5")
        );
    }

    /// An unlimited `max_depth` is capped for the point-based render and
    /// kept for the path tracer; a `max_depth` of 1 or 2 is no bounce.
    #[test]
    fn an_unlimited_depth_is_capped_for_the_point_based_render_alone() {
        let r = RenderOptions::default().resolve(&scene(None, Some(-1)), &Flags::default());
        assert_eq!(r.options.bounces, UNLIMITED_BOUNCES);
        let (unbounded, _) = file_bounces(scene(None, Some(-1)).file_settings, None, false);
        assert_eq!(unbounded, Some(-1));
        let direct = RenderOptions::default().resolve(&scene(None, Some(2)), &Flags::default());
        assert_eq!(direct.options.bounces, 0);
    }

    /// A file without a density or budget gets the default budget; a named
    /// scene keeps the base's density; a flag wins over both.
    #[test]
    fn a_file_gets_the_default_budget_and_a_named_scene_its_density() {
        let base = RenderOptions::default();
        let s = scene(None, None);
        let file = base.resolve(&s, &Flags::default()).options;
        assert_eq!(file.surfel_budget, Some(DEFAULT_SURFEL_BUDGET));
        let named = base
            .resolve(
                &s,
                &Flags {
                    named: true,
                    ..Flags::default()
                },
            )
            .options;
        assert_eq!((named.surfel_budget, named.density), (None, base.density));
        let dense = base
            .resolve(
                &s,
                &Flags {
                    density: Some(500.0),
                    ..Flags::default()
                },
            )
            .options;
        assert_eq!((dense.surfel_budget, dense.density), (None, 500.0));
        let budget = Flags {
            surfel_budget: Some(1000),
            named: true,
            ..Flags::default()
        };
        assert_eq!(base.resolve(&s, &budget).options.surfel_budget, Some(1000));
    }
}
