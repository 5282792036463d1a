//! The camera as the command line gives it: `--resolution`, `--camera-*`
//! and `--fov`, parsed (`overrides` applies them to a scene).

use clap::Args;

/// The camera as the command line changes it: size, place, field of view.
#[derive(Args, Clone, Debug, Default)]
pub struct ViewArgs {
    /// Image size WxH instead of the scene's, the field of view kept on
    /// the camera's axis (e.g. 1920x1080).
    #[arg(long, value_name = "WxH", value_parser = resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Where the camera stands instead of the scene's (e.g. 0,1.5,4).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub camera_origin: Option<[f32; 3]>,
    /// The point the camera looks at instead of the scene's.
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub camera_target: Option<[f32; 3]>,
    /// Field of view in degrees on the camera's axis, instead of the scene's.
    #[arg(long, value_name = "DEGREES")]
    pub fov: Option<f32>,
}

/// `X,Y,Z`: three finite numbers.
fn point(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("{s:?}: expected three finite numbers X,Y,Z"))?;
    <[f32; 3]>::try_from(v).map_err(|v| format!("{s:?}: {} numbers, expected X,Y,Z", v.len()))
}

/// The largest side `--resolution` accepts.
const MAX_SIDE: u32 = 16_384;

/// `--resolution WxH`: two whole numbers from 1 to [`MAX_SIDE`].
fn resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .trim()
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("{s:?}: expected WxH, e.g. 1920x1080"))?;
    let side = |t: &str, what: &str| match t.trim().parse::<i64>() {
        Ok(n) if (1..=i64::from(MAX_SIDE)).contains(&n) => Ok(n as u32),
        Ok(n) => Err(format!("{s:?}: a {what} of {n} pixels, expected 1 to {MAX_SIDE}")),
        Err(_) => Err(format!("{s:?}: {t:?} is not a whole number of pixels")),
    };
    Ok((side(w, "width")?, side(h, "height")?))
}
