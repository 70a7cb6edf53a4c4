//! `ubf frames` and `ubf pipeline`: recording stereo pairs, and replaying
//! them through the feature pipeline and egomotion.

use super::{CliError, Exit, Outcome};
use crate::scenario::{Scenario, Work};
use std::path::Path;
use ubf_core::Registry;

/// How `ubf frames` records.
pub(super) struct FramesRequest<'a> {
    /// The scenario file.
    pub file: &'a Path,
    /// Where the pairs go.
    pub out: &'a Path,
    /// The seed, if not the scenario's.
    pub seed: Option<u64>,
    /// At most this many pairs.
    pub max: usize,
    /// Record beyond the bound on bytes.
    pub huge: bool,
    /// Replace an earlier recording in `out`.
    pub overwrite: bool,
}

/// Records a scenario's rendered pairs into `out`.
pub(super) fn frames(registry: &Registry, request: FramesRequest) -> Outcome {
    let FramesRequest { file, out, seed, max, huge, overwrite } = request;
    let loaded = if huge { Scenario::load_unbounded(registry, file) } else { Scenario::load(registry, file) };
    let scenario = loaded.map_err(CliError::bad_input)?;
    let bytes = crate::frames::recording_bytes(&scenario, max);
    if bytes > Work::MOST_RECORDING_BYTES && !huge {
        return Err(CliError::bad_input(format!(
            "up to {} of images (PNG compresses rendered noise little), more than {}; \
             lower --max-frames, or pass --huge to record them anyway",
            Work::bytes_text(bytes),
            Work::bytes_text(Work::MOST_RECORDING_BYTES)
        )));
    }
    super::out_dir::prepare(out, &super::out_dir::FRAMES, overwrite)?;
    let count = crate::frames::record(&scenario, seed.unwrap_or(scenario.seed), out, max).map_err(CliError::failed)?;
    println!("{count} stereo pairs in {}", out.display());
    Ok(Exit::Success)
}

/// Replays a directory of pairs, timing the stages and, with ground truth,
/// measuring the estimate.
pub(super) fn pipeline(dir: &Path, options: &crate::frames::ReplayOptions, json: bool, plot: Option<&Path>) -> Outcome {
    let replay = crate::frames::replay(dir, options).map_err(CliError::bad_input)?;
    if let Some(path) = plot {
        crate::plot::draw_paths(&replay.estimate, replay.truth.as_deref(), path).map_err(CliError::failed)?;
    }
    super::show(&replay.report, json)?;
    Ok(Exit::Success)
}

/// A number of stereo pairs to record: at least one (a recording of none
/// would still be a directory of one pair and its calibration).
pub(super) fn parse_frame_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("expected a number of pairs, at least 1; got {text:?}")),
    }
}

/// A speed or turn-rate limit: finite and positive.
pub(super) fn parse_limit(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1e4 => Ok(v),
        _ => Err(format!("expected a number above 0 and at most 10 000; got {text:?}")),
    }
}

/// A disparity offset, px: any finite number (the camera's check bounds it
/// by the image width).
pub(super) fn parse_offset(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("expected a number of pixels; got {text:?}")),
    }
}
