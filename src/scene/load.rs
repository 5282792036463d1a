//! Scene files: Mitsuba 3 XML, OBJ + MTL, PLY.

use std::path::Path;

use super::{Scene, SceneError, builtin};

/// Loads a scene file, choosing the format by extension (`.xml`, `.obj`, `.ply`).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    Err(SceneError::Unsupported {
        path: path.to_path_buf(),
        line: 0,
        what: "scene files are not read yet".into(),
    })
}

/// A built-in scene by name, else a file by path.
pub fn resolve(name_or_path: &str) -> Result<Scene, SceneError> {
    match builtin::scene(name_or_path) {
        Ok(s) => Ok(s),
        Err(e) if Path::new(name_or_path).exists() => load(Path::new(name_or_path))
            .map_err(|_| e)
            .or_else(|_| load(Path::new(name_or_path))),
        Err(e) => Err(e),
    }
}
