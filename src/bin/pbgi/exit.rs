//! One exit status per class of error, so that a script or a render farm's
//! queue can tell a bad command line from a bad file from a defect:
//!
//! | status | class |
//! | --- | --- |
//! | 0 | done |
//! | 1 | the work failed: a self-check, a value that is not finite, anything unforeseen |
//! | 2 | the command line: an option out of range, contradictory or unknown (clap's own errors too) |
//! | 3 | the input: a scene, mesh, texture, image or tree file missing or invalid |
//! | 4 | the output could not be written |

use std::error::Error;
use std::fmt;

use pbgi::render::RenderError;
use pbgi::report::ReportError;
use pbgi::scene::SceneError;
use pbgi::tree::TreeFileError;

/// The statuses, named.
pub const FAILED: u8 = 1;
/// See the module's table.
pub const USAGE: u8 = 2;
/// See the module's table.
pub const INPUT: u8 = 3;
/// See the module's table.
pub const OUTPUT: u8 = 4;

/// An error of class `code`, with its message.
#[derive(Debug)]
pub struct Classed {
    code: u8,
    message: String,
}

impl fmt::Display for Classed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl Error for Classed {}

fn classed(code: u8, message: impl Into<String>) -> Box<dyn Error> {
    Box::new(Classed {
        code,
        message: message.into(),
    })
}

/// A command line that asks for something impossible.
pub fn usage(message: impl Into<String>) -> Box<dyn Error> {
    classed(USAGE, message)
}

/// An input that cannot be read.
pub fn input(message: impl Into<String>) -> Box<dyn Error> {
    classed(INPUT, message)
}

/// An output that cannot be written.
pub fn output(message: impl Into<String>) -> Box<dyn Error> {
    classed(OUTPUT, message)
}

/// The exit status of `e`.
pub fn code(e: &(dyn Error + 'static)) -> u8 {
    if let Some(c) = e.downcast_ref::<Classed>() {
        return c.code;
    }
    if e.is::<SceneError>() || e.is::<TreeFileError>() {
        return INPUT;
    }
    if let Some(r) = e.downcast_ref::<ReportError>() {
        return match r {
            ReportError::Render(r) => render(r),
            _ => INPUT,
        };
    }
    if let Some(k) = e.downcast_ref::<pbgi::Error>() {
        return kernel(k);
    }
    match e.downcast_ref::<RenderError>() {
        Some(r) => render(r),
        None => FAILED,
    }
}

fn render(e: &RenderError) -> u8 {
    match e {
        RenderError::Scene(_) => INPUT,
        RenderError::Kernel(k) => kernel(k),
        RenderError::Crop(_) | RenderError::TreeMismatch { .. } => USAGE,
        _ => FAILED,
    }
}

fn kernel(e: &pbgi::Error) -> u8 {
    match e {
        pbgi::Error::InvalidParameter { .. } | pbgi::Error::UnknownScheme { .. } | pbgi::Error::Isa(_) => {
            USAGE
        }
        pbgi::Error::InvalidSurfel { .. }
        | pbgi::Error::InvalidReceiver { .. }
        | pbgi::Error::TooManySurfels { .. } => INPUT,
        _ => FAILED,
    }
}
