//! Scene names: the built-in scenes, the scenes built on files that
//! `scripts/fetch-scenes.sh` fetches (never committed) and where they are
//! looked for, and resolving a name or a path to a scene.
//!
//! The folder is `$PBGI_SCENE_DIR`, else `scenes/` in this repository.
//! Asking for a fetched scene whose file is missing is a
//! [`SceneError::MissingSceneData`] naming the file and the script.

#[cfg(feature = "formats")]
use std::path::{Path, PathBuf};

use super::builtin;
#[cfg(feature = "formats")]
use super::{Scene, SceneError, fetched, formats::load};

/// Names of the scenes built on fetched files.
#[cfg(feature = "formats")]
pub const FETCHED: [&str; 5] = [
    "bunny",
    "bunny-glossy",
    "sponza",
    "sponza-bump",
    "cornell-box-embree",
];

/// The environment variable naming the scene folder.
#[cfg(feature = "formats")]
pub const SCENE_DIR_ENV: &str = "PBGI_SCENE_DIR";

/// The scene folder: `$PBGI_SCENE_DIR` when set and not empty; else
/// `scenes/` in the repository this library was built from, while that
/// folder exists (a clone, where `scripts/fetch-scenes.sh` puts them); else,
/// for an installed binary whose build tree is gone, the user's data
/// folder: `$XDG_DATA_HOME/pbgi/scenes` or `~/.local/share/pbgi/scenes`
/// (`%APPDATA%\pbgi\scenes` on Windows).
#[cfg(feature = "formats")]
pub fn scene_dir() -> PathBuf {
    let var = |name: &str| {
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    let repository = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    choose_scene_dir(
        var(SCENE_DIR_ENV),
        repository.is_dir().then_some(repository),
        var("XDG_DATA_HOME")
            .or_else(|| var("HOME").map(|h| h.join(".local/share")))
            .or_else(|| var("APPDATA")),
    )
}

/// [`scene_dir`]'s choice among the folder named in the environment, the
/// repository's (if it exists) and the user's data folder.
#[cfg(feature = "formats")]
fn choose_scene_dir(named: Option<PathBuf>, repository: Option<PathBuf>, data: Option<PathBuf>) -> PathBuf {
    named
        .or(repository)
        .or_else(|| data.map(|d| d.join("pbgi").join("scenes")))
        .unwrap_or_else(|| PathBuf::from("scenes"))
}

/// The files scene `name` needs, relative to the scene folder (`None` for an unknown name).
#[cfg(feature = "formats")]
pub fn files(name: &str) -> Option<&'static [&'static str]> {
    Some(match name {
        "bunny" | "bunny-glossy" => &["bunny/bunny.obj"],
        "sponza" | "sponza-bump" => &["sponza/sponza.obj"],
        "cornell-box-embree" => &[
            "cornell-box-embree/cornell_box.obj",
            "cornell-box-embree/cornell_box.mtl",
        ],
        _ => return None,
    })
}

/// The first file of scene `name` missing from `dir` (`None`: all present, or an unknown name).
#[cfg(feature = "formats")]
fn missing_in(name: &str, dir: &Path) -> Option<PathBuf> {
    files(name)?.iter().map(|f| dir.join(f)).find(|p| !p.is_file())
}

/// Whether scene `name` is known and all its files are in `dir`.
#[cfg(feature = "formats")]
pub fn is_present_in(name: &str, dir: &Path) -> bool {
    files(name).is_some() && missing_in(name, dir).is_none()
}

/// The fetched scenes whose files are in `dir`.
#[cfg(feature = "formats")]
pub fn available_in(dir: &Path) -> Vec<String> {
    FETCHED
        .iter()
        .filter(|n| is_present_in(n, dir))
        .map(|n| n.to_string())
        .collect()
}

/// Fetched scene `name` from the scene folder ([`scene_dir`]).
#[cfg(feature = "formats")]
pub fn fetched_scene(name: &str) -> Result<Scene, SceneError> {
    fetched_scene_in(name, &scene_dir())
}

/// Fetched scene `name` with its files read from `dir`.
#[cfg(feature = "formats")]
pub fn fetched_scene_in(name: &str, dir: &Path) -> Result<Scene, SceneError> {
    if files(name).is_none() {
        return Err(SceneError::UnknownScene {
            name: name.to_string(),
            builtins: builtin::NAMES.iter().chain(FETCHED.iter()).copied().collect(),
        });
    }
    if let Some(file) = missing_in(name, dir) {
        return Err(SceneError::MissingSceneData {
            scene: name.to_string(),
            file,
        });
    }
    let scene = match name {
        "bunny" => fetched::bunny(dir, false)?,
        "bunny-glossy" => fetched::bunny(dir, true)?,
        "sponza" => fetched::sponza(dir, false)?,
        "sponza-bump" => fetched::sponza(dir, true)?,
        _ => fetched::cornell_box_embree(dir)?,
    };
    scene.validate()?;
    Ok(scene)
}

/// Whether `name` is a scene name (built in or fetched) rather than a file.
pub fn is_named(name: &str) -> bool {
    #[cfg(feature = "formats")]
    if files(name).is_some() {
        return true;
    }
    builtin::NAMES.contains(&name)
}

/// A built-in scene by name, else a fetched scene by name (from the scene
/// folder, [`scene_dir`]), else a file by path.
#[cfg(feature = "formats")]
pub fn resolve(name_or_path: &str) -> Result<Scene, SceneError> {
    resolve_in(name_or_path, &scene_dir())
}

/// As [`resolve`], with fetched scenes read from `scene_dir`. A fetched
/// scene's name with its file missing is [`SceneError::MissingSceneData`].
#[cfg(feature = "formats")]
pub fn resolve_in(name_or_path: &str, scene_dir: &Path) -> Result<Scene, SceneError> {
    if builtin::NAMES.contains(&name_or_path) {
        return builtin::scene(name_or_path);
    }
    if files(name_or_path).is_some() {
        return fetched_scene_in(name_or_path, scene_dir);
    }
    let p = Path::new(name_or_path);
    if p.exists() {
        load(p)
    } else if p.extension().is_some() || p.components().count() > 1 {
        // Written as a file (an extension, a folder): say so, not which
        // names exist.
        Err(SceneError::Io {
            path: p.to_path_buf(),
            message: "not found".into(),
        })
    } else {
        Err(SceneError::UnknownScene {
            name: name_or_path.to_string(),
            builtins: builtin::NAMES.iter().chain(FETCHED.iter()).copied().collect(),
        })
    }
}

/// Names of the scenes usable now: the built-in ones always, the fetched ones
/// (see `scripts/fetch-scenes.sh`) when their files are in the scene folder
/// (`PBGI_SCENE_DIR`, else `scenes/` in the repository).
pub fn available_scenes() -> Vec<String> {
    #[cfg(feature = "formats")]
    return available_scenes_in(&scene_dir());
    #[cfg(not(feature = "formats"))]
    builtin::NAMES.iter().map(|s| s.to_string()).collect()
}

/// As [`available_scenes`], with fetched scenes looked for in `dir`.
#[cfg(feature = "formats")]
pub fn available_scenes_in(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = builtin::NAMES.iter().map(|s| s.to_string()).collect();
    names.extend(available_in(dir));
    names
}

#[cfg(all(test, feature = "formats"))]
mod tests {
    use super::*;

    /// The environment's folder first, then the repository's while it
    /// exists, then the user's data folder, then `scenes/` here.
    #[test]
    fn an_installed_binary_looks_in_the_user_s_data_folder() {
        let p = |s: &str| Some(PathBuf::from(s));
        assert_eq!(
            choose_scene_dir(p("/e"), p("/repo/scenes"), p("/d")),
            PathBuf::from("/e")
        );
        assert_eq!(
            choose_scene_dir(None, p("/repo/scenes"), p("/d")),
            PathBuf::from("/repo/scenes")
        );
        assert_eq!(
            choose_scene_dir(None, None, p("/d")),
            PathBuf::from("/d/pbgi/scenes")
        );
        assert_eq!(choose_scene_dir(None, None, None), PathBuf::from("scenes"));
    }
}
