//! `pbgi render --cache`: the world-space cache's records read before a
//! render and written after it, so that frames, runs and machines share them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use pbgi::render::{Frame, Gathers, RenderOptions};

use crate::args::Res;
use crate::exit;

/// A render's cache file, and what became of it.
pub struct CacheFile {
    path: PathBuf,
    frozen: bool,
    /// Records read from it, and the seconds that took.
    read: Option<(usize, f64)>,
}

impl CacheFile {
    /// Takes up the records of `path` into `frame` where the file exists
    /// (it must, when `frozen`). Errors name the file.
    pub fn open(path: &Path, frozen: bool, opts: &RenderOptions, frame: &mut Frame<'_>) -> Res<Self> {
        if !matches!(opts.gathers, Gathers::Cache { .. }) {
            return Err(exit::usage(format!(
                "--cache {}: a cache file serves a render with --gathers cache",
                path.display()
            )));
        }
        let mut out = CacheFile {
            path: path.to_path_buf(),
            frozen,
            read: None,
        };
        let file = match std::fs::File::open(path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && !frozen => return Ok(out),
            Err(e) => return Err(exit::input(format!("{}: {e}", path.display()))),
        };
        // A device or a pipe could be endless.
        if !file.metadata().is_ok_and(|m| m.is_file()) {
            return Err(exit::input(format!("{}: not a regular file", path.display())));
        }
        let t0 = Instant::now();
        let n = frame
            .load_cache(std::io::BufReader::new(file))
            .map_err(|e| exit::input(format!("{}: {e}", path.display())))?;
        out.read = Some((n, t0.elapsed().as_secs_f64()));
        Ok(out)
    }

    /// Writes `frame`'s records back (unless frozen), by a file beside it
    /// renamed over it, so that a reader never sees half a file; prints
    /// what was read, gathered and written.
    pub fn close(&self, frame: &Frame<'_>) -> Res<()> {
        let before = self.read.map_or(0, |r| r.0);
        let now = frame.cache_len();
        if let Some((n, seconds)) = self.read {
            println!(
                "cache: {n} records read from {} ({seconds:.3} s to read and check)",
                self.path.display()
            );
        }
        if self.frozen {
            println!(
                "cache: {} records gathered that the frozen {} lacks (kept for this run alone)",
                now - before,
                self.path.display()
            );
            return Ok(());
        }
        let mut name = self.path.clone().into_os_string();
        name.push(".part");
        let part = PathBuf::from(name);
        let write = || -> Result<usize, Box<dyn std::error::Error>> {
            let mut w = std::io::BufWriter::new(std::fs::File::create(&part)?);
            let n = frame.save_cache(&mut w)?;
            drop(w);
            std::fs::rename(&part, &self.path)?;
            Ok(n)
        };
        let n = write().map_err(|e| exit::output(format!("{}: {e}", self.path.display())))?;
        println!(
            "cache: wrote {} ({n} records, {} gathered by this run)",
            self.path.display(),
            now - before
        );
        Ok(())
    }
}
