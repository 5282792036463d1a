//! Progress bars: one per stage of a render's `pre.`, one over the frame's
//! tiles, the path tracer's rows or the benchmark's passes.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `unit`s with `message`. Its time left is the elapsed time
/// scaled by the fraction still to do, shown from 5 % done on: a rate over
/// the last few steps read "19h left" in a 17 s stage whose first tiles were
/// its slowest. Off a terminal the bar is hidden and [`tick`] prints plain
/// lines instead.
pub(crate) fn progress_bar(unit: &str, message: String) -> ProgressBar {
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} {{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{left}}"
        ))
        .expect("valid template")
        .with_key(
            "left",
            |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let f = state.fraction() as f64;
                let elapsed = state.elapsed().as_secs_f64();
                let _ = if f < 0.05 || elapsed < 1.0 {
                    write!(w, "estimating the time left")
                } else {
                    let left = (elapsed * (1.0 - f) / f).round() as u64;
                    write!(w, "{}:{:02} left", left / 60, left % 60)
                };
            },
        )
        .progress_chars("=> "),
    );
    bar.set_message(message);
    bar
}

pub(crate) fn tick(bar: &ProgressBar, done: usize, total: usize) {
    if done == 0 {
        bar.set_length(total as u64);
    }
    // Reports from several threads may arrive out of order.
    bar.set_position((done as u64).max(bar.position()));
    // Off a terminal, for logs: a line when the stage is done, and one at
    // each tenth of a stage that has run for 10 s.
    if bar.is_hidden() && total > 0 && done > 0 {
        let (before, now) = ((done - 1) * 10 / total, done * 10 / total);
        let elapsed = bar.elapsed().as_secs_f64();
        if done >= total {
            eprintln!("{}: done in {elapsed:.1} s", bar.message());
        } else if now > before && elapsed >= 10.0 {
            eprintln!("{}: {now}0 % in {elapsed:.1} s", bar.message());
        }
    }
}

/// A bar per stage of a render's `pre.` ([`pbgi::render::Progress`]), each
/// replaced by the next stage's as it begins.
pub(crate) struct StageBars {
    scene: String,
    current: std::sync::Mutex<Option<(&'static str, ProgressBar)>>,
}

impl StageBars {
    pub(crate) fn new(scene: &str) -> Self {
        Self {
            scene: scene.to_string(),
            current: std::sync::Mutex::new(None),
        }
    }

    pub(crate) fn report(&self, stage: &'static str, done: usize, total: usize) {
        let mut current = self.current.lock().unwrap_or_else(|e| e.into_inner());
        if current.as_ref().is_none_or(|(s, _)| *s != stage) {
            if let Some((_, bar)) = current.take() {
                bar.finish_and_clear();
            }
            // The library's stages count surfels (their direct light),
            // gathers (at groups of surfels; a total of 0 while their
            // count is not known yet), or one step.
            let unit = match (stage.starts_with("surfels"), total != 1) {
                (true, _) => "surfels",
                (false, true) => "gathers",
                (false, false) => "step",
            };
            *current = Some((stage, progress_bar(unit, format!("{}: {stage}", self.scene))));
        }
        if let Some((_, bar)) = current.as_ref() {
            tick(bar, done, total);
        }
    }

    pub(crate) fn finish(&self) {
        if let Some((_, bar)) = self.current.lock().unwrap_or_else(|e| e.into_inner()).take() {
            bar.finish_and_clear();
        }
    }
}
