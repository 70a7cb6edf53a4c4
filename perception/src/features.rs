//! Landmarks from real images (thesis §2.3, §4.4.6): corners found by the
//! FAST segment test, described by 256 BRIEF-style intensity comparisons,
//! matched between the two rectified images along rows with a distance
//! threshold and the distance-ratio test (eq. 8–11), refined to sub-pixel
//! disparity by block matching, and triangulated (eq. 12–14).
//!
//! The output is the same [`LandmarkObservation`]s the geometric camera
//! model produces, so the tracking list and the egomotion estimators take
//! either without knowing which.
//!
//! Why not SIFT, as the thesis did: its robot could not run egomotion in
//! real time, and ours must. The cameras stay upright and level on a planar
//! robot and frames are half a second apart, so neither rotation nor scale
//! invariance is needed; a binary descriptor compares in a few nanoseconds
//! (Hamming distance on four words) where a float one takes a hundred.

use crate::stereo::StereoCamera;
use image::GrayImage;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;
use ubf_core::{Descriptor, LandmarkObservation, StereoPixels};

/// The detector's and matcher's settings, as written in a scenario or robot
/// file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FeatureConfig {
    /// FAST: a corner needs 9 contiguous pixels of its 16-pixel circle all
    /// brighter or all darker than it by this many grey levels.
    pub fast_threshold: u8,
    /// Where the image has too little contrast for `fast_threshold` (blur,
    /// a dim scene): every square cell of `cell_px` without a corner is
    /// searched again at this lower threshold, and what it finds ranks
    /// after the corners found at `fast_threshold`. Equal to
    /// `fast_threshold` turns it off.
    pub min_fast_threshold: u8,
    /// The side of those cells, px.
    pub cell_px: u32,
    /// At most this many corners per image, the strongest.
    pub max_features: usize,
    /// Largest Hamming distance of an accepted match, of 256 bits (eq. 10).
    pub max_distance: u32,
    /// The best match must be nearer than this share of the second best
    /// (the distance-ratio test, eq. 11).
    pub ratio: f64,
    /// Rows a stereo match may be apart (rectification error), px, about
    /// the vertical offset between the images.
    pub row_tolerance_px: u32,
    /// Rows searched above and below the running estimate of how far the
    /// right image sits below the left (a rig out of line) for each pair's
    /// own estimate; 0 turns the estimate and its correction off.
    pub max_row_offset_px: u32,
    /// Smallest disparity searched, px.
    pub min_disparity_px: f64,
    /// Largest disparity searched, px.
    pub max_disparity_px: f64,
}

impl ubf_core::config::Check for FeatureConfig {
    /// Settings the matcher can work with: at least one feature, a Hamming
    /// distance within the 256 bits, a ratio in (0, 1], a row tolerance
    /// of at most 64 px and a disparity range that is one.
    fn check(&self) -> Result<(), String> {
        if !(1..=100_000).contains(&self.max_features) {
            return Err(format!("max_features: {}; 1 to 100000", self.max_features));
        }
        if self.min_fast_threshold > self.fast_threshold {
            return Err(format!(
                "min_fast_threshold: {}; at most fast_threshold ({})",
                self.min_fast_threshold, self.fast_threshold
            ));
        }
        if !(8..=4096).contains(&self.cell_px) {
            return Err(format!("cell_px: {}; 8 to 4096", self.cell_px));
        }
        if self.max_distance > 256 {
            return Err(format!("max_distance: {}; a descriptor has 256 bits", self.max_distance));
        }
        if !(self.ratio > 0.0 && self.ratio <= 1.0) {
            return Err(format!("ratio: {}; within (0, 1]", ubf_core::config::shown(self.ratio)));
        }
        if self.row_tolerance_px > 64 {
            return Err(format!("row_tolerance_px: {}; at most 64", self.row_tolerance_px));
        }
        if self.max_row_offset_px > 64 {
            return Err(format!("max_row_offset_px: {}; at most 64", self.max_row_offset_px));
        }
        let (low, high) = (self.min_disparity_px, self.max_disparity_px);
        if !(low.is_finite() && high.is_finite() && low >= 0.0 && low < high) {
            return Err(format!("min_disparity_px {low}, max_disparity_px {high}: need 0 ≤ min < max"));
        }
        Ok(())
    }
}

impl Default for FeatureConfig {
    fn default() -> Self {
        FeatureConfig {
            fast_threshold: 20,
            min_fast_threshold: 7,
            cell_px: 32,
            max_features: 1000,
            max_distance: 64,
            ratio: 0.8,
            row_tolerance_px: 1,
            max_row_offset_px: 3,
            min_disparity_px: 1.0,
            max_disparity_px: 200.0,
        }
    }
}

/// A described corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Feature {
    /// Column, px.
    pub x: u32,
    /// Row, px.
    pub y: u32,
    /// FAST score: the summed contrast of its arc beyond the threshold.
    pub score: u32,
    /// The binary descriptor.
    pub descriptor: Descriptor,
}

/// The 16-pixel Bresenham circle of radius 3, clockwise from the top.
const CIRCLE: [(i32, i32); 16] = [
    (0, -3),
    (1, -3),
    (2, -2),
    (3, -1),
    (3, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 3),
    (-1, 3),
    (-2, 2),
    (-3, 1),
    (-3, 0),
    (-3, -1),
    (-2, -2),
    (-1, -3),
];

/// Half the side of the descriptor's patch; corners nearer the border than
/// this (plus the smoothing) are not described.
const PATCH: i32 = 12;
/// Margin kept from the image border.
const BORDER: u32 = (PATCH + 3) as u32;

/// The 256 point pairs of the descriptor: offsets drawn once from an
/// isotropic Gaussian (σ = patch/2.5, BRIEF's "G II"), with a fixed seed so
/// every run and every image uses the same tests.
fn pattern() -> &'static [[i8; 4]; 256] {
    static PATTERN: OnceLock<[[i8; 4]; 256]> = OnceLock::new();
    PATTERN.get_or_init(|| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x0b71_ef00);
        let sigma = f64::from(PATCH) / 2.5;
        let mut gaussian = || {
            // Box–Muller; clamped to the patch.
            let (a, b): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random());
            let g = (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos() * sigma;
            g.round().clamp(-f64::from(PATCH), f64::from(PATCH)) as i8
        };
        std::array::from_fn(|_| [gaussian(), gaussian(), gaussian(), gaussian()])
    })
}

/// Whether 9 contiguous bits of the 16 (round the circle) are set.
fn has_arc_of_nine(mask: u32) -> bool {
    let doubled = mask | (mask << 16);
    let mut run = doubled;
    for k in 1..9 {
        run &= doubled >> k;
    }
    run != 0
}

/// FAST-9 corners with their scores, after 3×3 non-maximum suppression,
/// strongest first, at most `max` of them, none within the border margin.
pub fn detect(image: &GrayImage, threshold: u8, max: usize) -> Vec<(u32, u32, u32)> {
    detect_in(image, threshold, max, None)
}

/// Square cells of an image, those marked `true` taken (row by row,
/// `columns` to a row).
struct Cells<'a> {
    side: u32,
    columns: usize,
    taken: &'a [bool],
}

/// [`detect`], within the free `cells` only (if given) and the pixel
/// around them that their corners' suppression compares with: their
/// corners are those [`detect`] finds in them, without the cost of the
/// rest of the image.
fn detect_in(image: &GrayImage, threshold: u8, max: usize, cells: Option<Cells>) -> Vec<(u32, u32, u32)> {
    let (w, h) = image.dimensions();
    if w <= 2 * BORDER || h <= 2 * BORDER {
        return Vec::new();
    }
    let pixels = image.as_raw();
    let stride = w as isize;
    let offsets: [isize; 16] = CIRCLE.map(|(dx, dy)| dy as isize * stride + dx as isize);
    let t = i32::from(threshold);
    let mut scores = vec![0u32; (w * h) as usize];
    let mut corners = Vec::new();
    let (x0, x1) = (BORDER as usize, (w - BORDER) as usize);
    let mut candidate = vec![0u8; x1 - x0];
    // Per row of cells, the columns within a pixel of a free cell of it.
    let near_free: Vec<Vec<u8>> = cells.as_ref().map_or_else(Vec::new, |cells| {
        cells
            .taken
            .chunks(cells.columns)
            .map(|taken| {
                let free = |x: usize| u8::from(!taken[x / cells.side as usize]);
                (x0..x1).map(|x| free(x - 1) | free(x) | free((x + 1).min(w as usize - 1))).collect()
            })
            .collect()
    });
    let mut allowed = vec![1u8; x1 - x0];
    for y in BORDER..h - BORDER {
        let row = (y * w) as usize;
        if let Some(cells) = &cells {
            // Within a pixel of a free cell, in this row or the next one
            // up or down.
            let band = |y: u32| &near_free[(y / cells.side) as usize];
            for (((out, a), b), c) in allowed.iter_mut().zip(band(y - 1)).zip(band(y)).zip(band(y + 1)) {
                *out = a | b | c;
            }
            if allowed.iter().all(|&a| a == 0) {
                continue;
            }
        }
        // First, for the whole row at once (the compiler vectorises this
        // loop): an arc of nine of the sixteen ring points holds four
        // consecutive even-numbered ones, one of each opposite pair
        // (0 and 8, 2 and 10, 4 and 12, 6 and 14), so a pixel can only be
        // a corner if one of each of those pairs is brighter (or one of
        // each darker) than it by the threshold. On a textured image this
        // leaves a few per cent of the pixels, and the full ring is read
        // for those only.
        let at_offset = |(dx, dy): (i32, i32)| {
            let start = (row as isize + x0 as isize + dy as isize * stride + dx as isize) as usize;
            &pixels[start..start + (x1 - x0)]
        };
        let [p0, p2, p4, p6, p8, p10, p12, p14] = [0, 2, 4, 6, 8, 10, 12, 14].map(|k| at_offset(CIRCLE[k]));
        let centre = &pixels[row + x0..row + x1];
        for (i, (out, &allowed)) in candidate.iter_mut().zip(&allowed).enumerate() {
            let c = centre[i];
            let brighter = |p: &[u8]| p[i].saturating_sub(threshold) > c;
            let darker = |p: &[u8]| p[i].saturating_add(threshold) < c;
            let bright = (brighter(p0) | brighter(p8))
                & (brighter(p4) | brighter(p12))
                & (brighter(p2) | brighter(p10))
                & (brighter(p6) | brighter(p14));
            let dark = (darker(p0) | darker(p8))
                & (darker(p4) | darker(p12))
                & (darker(p2) | darker(p10))
                & (darker(p6) | darker(p14));
            *out = u8::from(bright | dark) & allowed;
        }
        // Eight flags at a time: most words of a row are all zero.
        for (chunk, flags) in candidate.chunks(8).enumerate() {
            let mut word = [0u8; 8];
            word[..flags.len()].copy_from_slice(flags);
            let mut bits = u64::from_le_bytes(word);
            while bits != 0 {
                let i = chunk * 8 + bits.trailing_zeros() as usize / 8;
                bits &= bits - 1;
                let x = (x0 + i) as u32;
                let at = row + x0 + i;
                let centre = i32::from(pixels[at]);
                let ring: [i32; 16] = offsets.map(|o| i32::from(pixels[(at as isize + o) as usize]));
                let (bright, dark) = (centre + t, centre - t);
                // Without branches: which side each ring point falls on
                // is what no branch predictor guesses. A point cannot be
                // both brighter and darker, so the two sums are those of
                // the points on either side.
                let (mut bright_mask, mut dark_mask, mut bright_sum, mut dark_sum) = (0u32, 0u32, 0u32, 0u32);
                for (k, &p) in ring.iter().enumerate() {
                    bright_mask |= u32::from(p > bright) << k;
                    dark_mask |= u32::from(p < dark) << k;
                    bright_sum += (p - bright).max(0) as u32;
                    dark_sum += (dark - p).max(0) as u32;
                }
                // Nine of sixteen cannot be both brighter and darker.
                let score = if has_arc_of_nine(bright_mask) {
                    bright_sum
                } else if has_arc_of_nine(dark_mask) {
                    dark_sum
                } else {
                    continue;
                };
                // Zero would read as "no corner" in the suppression.
                scores[at] = score + 1;
                corners.push((x, y));
            }
        }
    }
    let mut kept: Vec<(u32, u32, u32)> = corners
        .into_iter()
        .filter_map(|(x, y)| {
            let at = (y * w + x) as usize;
            let s = scores[at];
            // Strictly above the earlier neighbours, at least the later ones:
            // exactly one of a tied pair survives.
            let before = [at - w as usize - 1, at - w as usize, at - w as usize + 1, at - 1];
            let after = [at + 1, at + w as usize - 1, at + w as usize, at + w as usize + 1];
            (before.iter().all(|&n| scores[n] < s) && after.iter().all(|&n| scores[n] <= s)).then_some((x, y, s - 1))
        })
        .collect();
    // Strongest first; position breaks ties, so the order is deterministic.
    kept.sort_unstable_by(|a, b| b.2.cmp(&a.2).then((a.1, a.0).cmp(&(b.1, b.0))));
    kept.truncate(max);
    kept
}

/// The image smoothed by a 5×5 box, so single-pixel noise does not flip
/// the descriptor's comparisons.
fn smooth(image: &GrayImage) -> Vec<u8> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let src = image.as_raw();
    // Horizontal sums, then vertical, each a running sum; the two-pixel
    // rim keeps its values (descriptors never sample there).
    let mut rows = vec![0u16; w * h];
    if w >= 5 {
        for (src_row, row) in src.chunks_exact(w).zip(rows.chunks_exact_mut(w)) {
            let mut sum: u16 = src_row[..5].iter().map(|&p| u16::from(p)).sum();
            row[2] = sum;
            for x in 3..w - 2 {
                sum = sum + u16::from(src_row[x + 2]) - u16::from(src_row[x - 3]);
                row[x] = sum;
            }
        }
    }
    let mut out = src.clone();
    if h >= 5 {
        let mut sums: Vec<u32> = (0..w).map(|x| (0..5).map(|r| u32::from(rows[r * w + x])).sum()).collect();
        for y in 2..h - 2 {
            if y > 2 {
                for (x, sum) in sums.iter_mut().enumerate() {
                    *sum = *sum + u32::from(rows[(y + 2) * w + x]) - u32::from(rows[(y - 3) * w + x]);
                }
            }
            for x in 2..w.saturating_sub(2) {
                out[y * w + x] = (sums[x] / 25) as u8;
            }
        }
    }
    out
}

/// How far above an image's noise (its σ) the lowered threshold stays.
const NOISE_MARGIN: f64 = 5.0;

/// The σ of an image's pixel noise, grey levels: the median absolute
/// response to the 3 × 3 mask `[1 −2 1; −2 4 −2; 1 −2 1]`, which cancels
/// the image's smooth shading and leaves noise of 6σ (Immerkær 1996, with
/// the median so that edges and texture count little), over every other
/// pixel of every other row.
pub fn noise_sigma(image: &GrayImage) -> f64 {
    let (w, h) = (image.width() as usize, image.height() as usize);
    if w < 3 || h < 3 {
        return 0.0;
    }
    let p = image.as_raw();
    // A response is at most 16 · 255, so their median is read off a
    // histogram rather than by sorting.
    let mut histogram = vec![0u32; 16 * 255 + 1];
    let mut count = 0usize;
    for y in (1..h - 1).step_by(2) {
        let (above, here, below) = (&p[(y - 1) * w..y * w], &p[y * w..(y + 1) * w], &p[(y + 1) * w..(y + 2) * w]);
        let at = |row: &[u8], x: usize| i32::from(row[x]);
        for x in (1..w - 1).step_by(2) {
            let r = at(above, x - 1) + at(above, x + 1) + at(below, x - 1) + at(below, x + 1)
                - 2 * (at(above, x) + at(below, x) + at(here, x - 1) + at(here, x + 1))
                + 4 * at(here, x);
            histogram[r.unsigned_abs() as usize] += 1;
            count += 1;
        }
    }
    // The response of sorted rank count / 2.
    let middle = count / 2;
    let mut below = 0usize;
    let median = histogram
        .iter()
        .position(|&n| {
            below += n as usize;
            below > middle
        })
        .unwrap_or(0) as u32;
    // The median of |N(0, 6σ)| is 0.6745 · 6σ.
    f64::from(median) / (0.6745 * 6.0)
}

/// The corners [`extract`] describes: FAST at `fast_threshold`, strongest
/// first, and when they are fewer than `max_features`, after them those
/// found at `min_fast_threshold` (or five times the image's noise σ, if
/// that is more) in the cells of `cell_px` that had none (ORB-SLAM's
/// scheme, Mur-Artal et al. 2015), strongest first.
pub fn detect_adaptive(image: &GrayImage, config: &FeatureConfig) -> Vec<(u32, u32, u32)> {
    let mut corners = detect(image, config.fast_threshold, config.max_features);
    if corners.len() >= config.max_features || config.min_fast_threshold >= config.fast_threshold {
        return corners;
    }
    let cell = config.cell_px;
    let columns = image.width().div_ceil(cell) as usize;
    let mut occupied = vec![false; columns * image.height().div_ceil(cell) as usize];
    for &(x, y, _) in &corners {
        occupied[(y / cell) as usize * columns + (x / cell) as usize] = true;
    }
    // Never down into the noise: on the simulator's rendered corridor
    // (noise of σ 2 grey levels on smooth shading) the floor of 7 found
    // ten landmarks on plain walls and put a fifth of them off the
    // posters; five σ, 10 there, finds none of those.
    let floor = (NOISE_MARGIN * noise_sigma(image)).ceil().min(255.0) as u8;
    let lower = config.min_fast_threshold.max(floor);
    if lower >= config.fast_threshold {
        return corners;
    }
    let room = config.max_features - corners.len();
    corners.extend(
        detect_in(image, lower, usize::MAX, Some(Cells { side: cell, columns, taken: &occupied }))
            .into_iter()
            .filter(|&(x, y, _)| !occupied[(y / cell) as usize * columns + (x / cell) as usize])
            .take(room),
    );
    corners
}

/// Detects and describes the corners of `image`.
pub fn extract(image: &GrayImage, config: &FeatureConfig) -> Vec<Feature> {
    let corners = detect_adaptive(image, config);
    if corners.is_empty() {
        return Vec::new();
    }
    let smoothed = smooth(image);
    let w = image.width() as isize;
    // The pattern as offsets into this image's rows, once per image.
    let offsets: Vec<(isize, isize)> = pattern()
        .iter()
        .map(|&[x1, y1, x2, y2]| (isize::from(y1) * w + isize::from(x1), isize::from(y2) * w + isize::from(x2)))
        .collect();
    corners
        .into_iter()
        .map(|(x, y, score)| {
            let centre = y as isize * w + x as isize;
            let at = |offset: isize| smoothed[(centre + offset) as usize];
            let mut words = [0u64; 4];
            for (word, pairs) in words.iter_mut().zip(offsets.chunks_exact(64)) {
                // Without branches: the comparisons come out half and half,
                // which no branch predictor guesses.
                *word =
                    pairs.iter().enumerate().fold(0, |bits, (bit, &(a, b))| bits | (u64::from(at(a) < at(b)) << bit));
            }
            Feature { x, y, score, descriptor: Descriptor(words) }
        })
        .collect()
}

/// How the right camera's exposure differs from the left's: right grey
/// levels are mapped to the left's as `gain · right + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Exposure {
    gain: f32,
    offset: f32,
}

impl Exposure {
    /// The mapping that gives the right image the left one's mean and
    /// contrast, from every fourth pixel of each: two cameras with their
    /// own automatic exposure differ by a gain and an offset over the
    /// whole image, which biases block matching unless undone. Images with
    /// no contrast are left as they are.
    fn between(left: &GrayImage, right: &GrayImage) -> Exposure {
        let stats = |image: &GrayImage| {
            let (mut n, mut sum, mut squares) = (0.0f64, 0.0f64, 0.0f64);
            for &p in image.as_raw().iter().step_by(4) {
                let p = f64::from(p);
                (n, sum, squares) = (n + 1.0, sum + p, squares + p * p);
            }
            let mean = sum / n.max(1.0);
            (mean, (squares / n.max(1.0) - mean * mean).max(0.0).sqrt())
        };
        let ((mean_l, sd_l), (mean_r, sd_r)) = (stats(left), stats(right));
        if sd_l < 1.0 || sd_r < 1.0 {
            return Exposure { gain: 1.0, offset: 0.0 };
        }
        let gain = sd_l / sd_r;
        Exposure { gain: gain as f32, offset: (mean_l - gain * mean_r) as f32 }
    }
}

/// Sum of absolute differences of 7×7 blocks centred at `(xl, y)` in the
/// left image and `(xr, y + dy)` in the right (its grey levels mapped by
/// `exposure`), or `None` off the image.
#[allow(clippy::too_many_arguments)]
fn block_cost(
    left: &GrayImage,
    right: &GrayImage,
    exposure: Exposure,
    xl: i64,
    xr: i64,
    y: i64,
    dy: i64,
) -> Option<f32> {
    const R: i64 = 3;
    let (w, h) = (i64::from(left.width()), i64::from(left.height()));
    let yr = y + dy;
    if xr - R < 0 || xl + R >= w || xr + R >= w || xl - R < 0 || y - R < 0 || y + R >= h || yr - R < 0 || yr + R >= h {
        return None;
    }
    let (l, r) = (left.as_raw(), right.as_raw());
    let mut cost = 0.0f32;
    for k in -R..=R {
        let (row_l, row_r) = (((y + k) * w) as usize, ((yr + k) * w) as usize);
        for dx in -R..=R {
            let mapped = exposure.gain * f32::from(r[row_r + (xr + dx) as usize]) + exposure.offset;
            cost += (f32::from(l[row_l + (xl + dx) as usize]) - mapped).abs();
        }
    }
    Some(cost)
}

/// The vertical offset of a stereo match to a fraction of a pixel: block
/// costs at the matched columns with the right block `dy − 1`, `dy` and
/// `dy + 1` rows down, and a parabola through them; `None` when `dy` is
/// not the best of the three or the blocks leave the image.
fn refine_row_offset(
    left: &GrayImage,
    right: &GrayImage,
    exposure: Exposure,
    xl: u32,
    xr: u32,
    y: u32,
    dy: i64,
) -> Option<f64> {
    let cost = |d: i64| block_cost(left, right, exposure, i64::from(xl), i64::from(xr), i64::from(y), d);
    let (before, best, after) = (f64::from(cost(dy - 1)?), f64::from(cost(dy)?), f64::from(cost(dy + 1)?));
    let offset = parabola_vertex(before, best, after).filter(|_| best <= before && best <= after)?;
    Some(dy as f64 + offset)
}

/// Where a parabola through costs at −1, 0 and +1 has its minimum,
/// relative to 0; `None` when the three do not curve upwards.
fn parabola_vertex(before: f64, best: f64, after: f64) -> Option<f64> {
    let curvature = before - 2.0 * best + after;
    (curvature > 0.0).then(|| (before - after) / (2.0 * curvature))
}

/// The disparity of a stereo match to a fraction of a pixel: block matching
/// along the row (the right image's `dy` rows down) within two pixels of
/// the matched corners' disparity (the right image brought to the left's
/// exposure), then a parabola through the best cost and its neighbours.
fn refine_disparity(
    left: &GrayImage,
    right: &GrayImage,
    exposure: Exposure,
    xl: u32,
    xr: u32,
    y: u32,
    dy: i64,
) -> Option<f64> {
    let d0 = i64::from(xl) - i64::from(xr);
    let cost = |d: i64| block_cost(left, right, exposure, i64::from(xl), i64::from(xl) - d, i64::from(y), dy);
    let (mut best_d, mut best) = (d0, cost(d0)?);
    for d in d0 - 2..=d0 + 2 {
        if let Some(c) = cost(d) {
            if c < best {
                (best_d, best) = (d, c);
            }
        }
    }
    let (Some(before), Some(after)) = (cost(best_d - 1), cost(best_d + 1)) else {
        return Some(best_d as f64);
    };
    let offset = parabola_vertex(f64::from(before), f64::from(best), f64::from(after)).unwrap_or(0.0);
    Some(best_d as f64 + offset.clamp(-0.5, 0.5))
}

/// Stereo matches `(left, right)` between two rectified images' features:
/// for each left feature, the right features on its row (give or take the
/// tolerance) within the disparity range; the nearest descriptor is kept if
/// it is within the threshold and passes the ratio test against the second
/// nearest. A right feature claimed twice goes to the nearer claim.
pub fn match_stereo(left: &[Feature], right: &[Feature], config: &FeatureConfig) -> Vec<(usize, usize)> {
    match_stereo_rows(left, right, config, 0, config.row_tolerance_px).into_iter().map(|(i, j, _)| (i, j)).collect()
}

/// [`match_stereo`] with the right image's rows `offset` below the left's,
/// give or take `tolerance`: matches `(left, right, Hamming distance)`.
pub fn match_stereo_rows(
    left: &[Feature],
    right: &[Feature],
    config: &FeatureConfig,
    offset: i64,
    tolerance: u32,
) -> Vec<(usize, usize, u32)> {
    let rows = right.iter().map(|f| f.y).max().map_or(0, |m| m as usize + 1);
    let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); rows];
    for (i, f) in right.iter().enumerate() {
        by_row[f.y as usize].push(i);
    }
    let tolerance = i64::from(tolerance);
    let mut claims: Vec<(u32, usize, usize)> = Vec::new();
    for (i, l) in left.iter().enumerate() {
        let (mut best, mut second) = ((u32::MAX, usize::MAX), u32::MAX);
        let (y, x) = (i64::from(l.y) + offset, f64::from(l.x));
        let (first, last) = ((y - tolerance).max(0) as usize, (y + tolerance + 1).clamp(0, rows as i64) as usize);
        for row in by_row.iter().take(last).skip(first) {
            for &j in row {
                let disparity = x - f64::from(right[j].x);
                if disparity < config.min_disparity_px || disparity > config.max_disparity_px {
                    continue;
                }
                let d = l.descriptor.hamming(&right[j].descriptor);
                if d < best.0 {
                    second = best.0;
                    best = (d, j);
                } else if d < second {
                    second = d;
                }
            }
        }
        let found = best.1 != usize::MAX;
        if found
            && best.0 <= config.max_distance
            && (second == u32::MAX || f64::from(best.0) < config.ratio * f64::from(second))
        {
            claims.push((best.0, i, best.1));
        }
    }
    claims.sort_unstable();
    let mut taken = vec![false; right.len()];
    let mut matches: Vec<(usize, usize, u32)> = claims
        .into_iter()
        .filter(|&(_, _, j)| !std::mem::replace(&mut taken[j], true))
        .map(|(d, i, j)| (i, j, d))
        .collect();
    matches.sort_unstable();
    matches
}

/// What can be wrong with a stereo pair.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PipelineError {
    /// The images are not the size the calibration says.
    #[error("images are {left:?} and {right:?}, the calibration says {expected:?}")]
    WrongSize {
        /// The left image's width and height.
        left: (u32, u32),
        /// The right image's.
        right: (u32, u32),
        /// The calibration's.
        expected: (u32, u32),
    },
}

/// Pairs whose vertical offsets the running estimate takes the median of:
/// a rig's misalignment changes slowly, if at all.
const OFFSET_HISTORY: usize = 15;
/// Confident matches a pair needs for an estimate of its vertical offset.
const OFFSET_MATCHES: usize = 20;

/// What the pipeline found in one pair besides its landmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairReport {
    /// Corners detected in the left and the right image.
    pub corners: (usize, usize),
    /// This pair's estimate of how far the right image sits below the left
    /// (negative: above), px: the median over its confident matches, each
    /// to a fraction of a pixel; `None` with too few of them.
    pub row_offset_px: Option<f64>,
    /// The offset the matching used, whole rows: the running estimate over
    /// the latest pairs.
    pub applied_row_offset: i64,
}

/// From a rectified stereo pair to landmark observations.
///
/// A rig whose right camera sits a row or two out of line with the left
/// (a calibration gone stale) is found out and corrected on the fly: each
/// pair's confident matches, searched `max_row_offset_px` rows up and
/// down, give the offset as their median row difference, and the pairs
/// are matched and refined along rows moved by the median over the latest
/// pairs. [`StereoPipeline::row_offset`] says what it is, so that a user
/// knows the rig needs recalibrating.
#[derive(Debug)]
pub struct StereoPipeline {
    camera: StereoCamera,
    config: FeatureConfig,
    /// The latest pairs' vertical offsets, px.
    offsets: std::sync::Mutex<std::collections::VecDeque<f64>>,
}

impl Clone for StereoPipeline {
    fn clone(&self) -> Self {
        StereoPipeline {
            camera: self.camera,
            config: self.config,
            offsets: std::sync::Mutex::new(self.recent_offsets()),
        }
    }
}

impl StereoPipeline {
    /// A pipeline for `camera`'s images.
    pub fn new(camera: StereoCamera, config: FeatureConfig) -> Self {
        StereoPipeline { camera, config, offsets: Default::default() }
    }

    /// The settings.
    pub fn config(&self) -> &FeatureConfig {
        &self.config
    }

    fn recent_offsets(&self) -> std::collections::VecDeque<f64> {
        self.offsets.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone()
    }

    /// How far the right image sits below the left by the latest pairs
    /// (the median of their estimates), px; `None` before any pair gave
    /// one.
    pub fn row_offset(&self) -> Option<f64> {
        let mut recent: Vec<f64> = self.recent_offsets().into();
        (!recent.is_empty()).then(|| crate::median(&mut recent))
    }

    /// The landmarks a pair of images shows: detected in both, matched,
    /// refined and triangulated, with the left image's descriptors.
    pub fn process(&self, left: &GrayImage, right: &GrayImage) -> Result<Vec<LandmarkObservation>, PipelineError> {
        self.process_pair(left, right).map(|(landmarks, _)| landmarks)
    }

    /// [`StereoPipeline::process`], with what the pair showed besides its
    /// landmarks.
    pub fn process_pair(
        &self,
        left: &GrayImage,
        right: &GrayImage,
    ) -> Result<(Vec<LandmarkObservation>, PairReport), PipelineError> {
        let expected = (self.camera.width_px, self.camera.height_px);
        if left.dimensions() != expected || right.dimensions() != expected {
            return Err(PipelineError::WrongSize { left: left.dimensions(), right: right.dimensions(), expected });
        }
        let (features_left, features_right) = (extract(left, &self.config), extract(right, &self.config));
        let exposure = Exposure::between(left, right);
        let prior = self.row_offset().map_or(0, |o| o.round() as i64);
        let row_offset = self.estimate_row_offset(left, right, exposure, &features_left, &features_right, prior);
        if let Some(offset) = row_offset {
            let mut recent = self.offsets.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            if recent.len() == OFFSET_HISTORY {
                recent.pop_front();
            }
            recent.push_back(offset);
        }
        // In whole rows: moving the right block by a fraction of a row
        // means interpolating it, which smooths it against the left one
        // (on KITTI 06 it took the end point from 1.11 % to 1.23 %).
        let applied = self.row_offset().map_or(0, |o| o.round() as i64);
        let report = PairReport {
            corners: (features_left.len(), features_right.len()),
            row_offset_px: row_offset,
            applied_row_offset: applied,
        };
        let mut out = Vec::new();
        for (i, j, _) in
            match_stereo_rows(&features_left, &features_right, &self.config, applied, self.config.row_tolerance_px)
        {
            let (l, r) = (&features_left[i], &features_right[j]);
            let Some(disparity) = refine_disparity(left, right, exposure, l.x, r.x, l.y, applied) else { continue };
            if disparity < self.config.min_disparity_px {
                continue;
            }
            // Pixel centres: the continuous coordinate of pixel k is k + ½.
            let u_left = f64::from(l.x) + 0.5;
            let pixels = StereoPixels { u_left, u_right: u_left - disparity, v: f64::from(l.y) + 0.5 };
            if let Some(point_cam) = self.camera.triangulate(&pixels) {
                out.push(LandmarkObservation { point_cam, pixels, descriptor: l.descriptor, source_id: None });
            }
        }
        Ok((out, report))
    }

    /// How far the right image sits below the left in this pair: matches
    /// searched `max_row_offset_px` rows about `prior`, those within half
    /// the distance threshold taken as confident, each one's row
    /// difference refined to a fraction of a pixel by block matching, and
    /// the median of them; `None` with fewer than [`OFFSET_MATCHES`], or
    /// when fewer than half lie within half a row of it.
    fn estimate_row_offset(
        &self,
        left: &GrayImage,
        right: &GrayImage,
        exposure: Exposure,
        features_left: &[Feature],
        features_right: &[Feature],
        prior: i64,
    ) -> Option<f64> {
        let search = self.config.max_row_offset_px;
        if search == 0 {
            return None;
        }
        let mut offsets: Vec<f64> = match_stereo_rows(
            features_left,
            features_right,
            &self.config,
            prior,
            search + self.config.row_tolerance_px,
        )
        .into_iter()
        .filter(|&(_, _, distance)| distance <= self.config.max_distance / 2)
        .filter_map(|(i, j, _)| {
            let (l, r) = (&features_left[i], &features_right[j]);
            let dy = i64::from(r.y) - i64::from(l.y);
            refine_row_offset(left, right, exposure, l.x, r.x, l.y, dy)
        })
        .collect();
        if offsets.len() < OFFSET_MATCHES {
            return None;
        }
        // Most of them must agree with the median to half a row, or the
        // pair (too blurred, too few corners) says nothing.
        let median = crate::median(&mut offsets);
        let agreeing = offsets.iter().filter(|o| (*o - median).abs() <= 0.5).count();
        (2 * agreeing >= offsets.len()).then_some(median)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    /// A grey image with dark squares: each square's four corners are FAST
    /// corners.
    fn squares(w: u32, h: u32, at: &[(u32, u32, u32)], shift: i32) -> GrayImage {
        GrayImage::from_fn(w, h, |x, y| {
            let inside = at.iter().any(|&(sx, sy, side)| {
                let x = x as i32 + shift;
                x >= sx as i32 && x < (sx + side) as i32 && y >= sy && y < sy + side
            });
            // A little texture so descriptors differ between squares.
            let texture = ((x * 7 + y * 13) % 5) as u8;
            Luma([if inside { 40 + texture } else { 200 - texture }])
        })
    }

    #[test]
    fn arcs_of_nine_round_the_circle() {
        assert!(has_arc_of_nine(0b1_1111_1111));
        assert!(has_arc_of_nine(0b1111_0000_0000_0001_1111 & 0xFFFF | 0b1111 << 12));
        assert!(!has_arc_of_nine(0b1111_1111));
        assert!(!has_arc_of_nine(0b0101_0101_0101_0101));
    }

    #[test]
    fn square_corners_are_found_once_each() {
        let image = squares(120, 100, &[(40, 30, 20)], 0);
        let corners = detect(&image, 20, 100);
        assert_eq!(corners.len(), 4, "{corners:?}");
        for (x, y, _) in corners {
            assert!([39, 40, 59, 60].contains(&x) && [29, 30, 49, 50].contains(&y), "({x}, {y})");
        }
        // A flat image has none, and neither does a tiny one.
        assert!(detect(&GrayImage::from_pixel(120, 100, Luma([90])), 20, 100).is_empty());
        assert!(detect(&GrayImage::new(20, 20), 20, 100).is_empty());
    }

    #[test]
    fn cells_without_corners_are_searched_again_at_the_lower_threshold() {
        // One square of contrast 160, one of 15: the faint one's corners
        // are under the threshold of 20 and over the fallback's 7.
        let image = GrayImage::from_fn(160, 100, |x, y| {
            let strong = (20..40).contains(&x) && (30..50).contains(&y);
            let faint = (100..120).contains(&x) && (30..50).contains(&y);
            Luma([if strong {
                40
            } else if faint {
                185
            } else {
                200
            }])
        });
        let fixed = FeatureConfig { min_fast_threshold: 20, ..FeatureConfig::default() };
        assert_eq!(detect_adaptive(&image, &fixed).len(), 4);
        let adaptive = detect_adaptive(&image, &FeatureConfig::default());
        assert_eq!(adaptive.len(), 8, "{adaptive:?}");
        // The strong square's corners rank first, and the faint square's
        // cells only are searched again (the strong one's found none more).
        assert!(adaptive[..4].iter().all(|&(x, _, _)| x < 60) && adaptive[4..].iter().all(|&(x, _, _)| x >= 99));
        // Enough corners at the threshold: no second search.
        let full = FeatureConfig { max_features: 4, ..FeatureConfig::default() };
        assert_eq!(detect_adaptive(&image, &full), detect(&image, 20, 4));
    }

    #[test]
    fn a_search_within_free_cells_finds_what_the_whole_image_has_in_them() {
        // Texture everywhere, every third cell taken: the corners of the
        // free cells, scores and suppression included, are the same.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let image = GrayImage::from_fn(200, 150, |x, y| {
            let texture = 100.0 + 40.0 * (0.4 * f64::from(x)).sin() * (0.3 * f64::from(y)).cos();
            Luma([(texture + rng.random_range(-12.0..12.0)).clamp(0.0, 255.0) as u8])
        });
        let (side, columns) = (32, 200u32.div_ceil(32) as usize);
        let taken: Vec<bool> = (0..columns * 150usize.div_ceil(32)).map(|i| i % 3 == 0).collect();
        let free = |&(x, y, _): &(u32, u32, u32)| !taken[(y / side) as usize * columns + (x / side) as usize];
        let whole: Vec<_> = detect(&image, 7, usize::MAX).into_iter().filter(free).collect();
        let within: Vec<_> = detect_in(&image, 7, usize::MAX, Some(Cells { side, columns, taken: &taken }))
            .into_iter()
            .filter(free)
            .collect();
        assert!(whole.len() > 50, "{}", whole.len());
        assert_eq!(within, whole);
    }

    #[test]
    fn the_noise_is_measured_through_smooth_shading_and_keeps_the_threshold_above_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut noisy = |sigma: f64| {
            GrayImage::from_fn(300, 200, |x, y| {
                let (a, b): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random());
                let n = (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos() * sigma;
                // A shading ramp the mask cancels.
                Luma([(60.0 + 0.3 * f64::from(x) + 0.2 * f64::from(y) + n).round().clamp(0.0, 255.0) as u8])
            })
        };
        for sigma in [2.0, 4.0] {
            let estimate = noise_sigma(&noisy(sigma));
            assert!((estimate / sigma - 1.0).abs() < 0.15, "σ {sigma}: {estimate}");
        }
        assert_eq!(noise_sigma(&GrayImage::from_pixel(50, 50, Luma([90]))), 0.0);
        // On noise of σ 2, the lowered threshold is 10, not 7.
        let image = noisy(2.0);
        let at_ten = detect(&image, 10, usize::MAX);
        assert!(detect_adaptive(&image, &FeatureConfig::default()).iter().all(|c| at_ten.contains(c)));
    }

    #[test]
    fn stereo_matches_recover_the_shift_and_triangulate() {
        // The right image is the left shifted 12 px: every match has
        // disparity 12, so depth f·T/12.
        let squares_at = [(60, 40, 24), (150, 90, 30), (250, 60, 20), (90, 150, 26)];
        let camera = StereoCamera { width_px: 320, height_px: 240, ..StereoCamera::default() };
        let left = squares(320, 240, &squares_at, 0);
        let right = squares(320, 240, &squares_at, 12);
        let pipeline = StereoPipeline::new(camera, FeatureConfig::default());
        let landmarks = pipeline.process(&left, &right).unwrap();
        assert!(landmarks.len() >= 12, "{}", landmarks.len());
        for l in &landmarks {
            assert!((l.pixels.disparity() - 12.0).abs() < 0.05, "{:?}", l.pixels);
            assert!((l.point_cam[1] - camera.focal_px * camera.baseline_m / 12.0).abs() < 0.1);
        }
        let wrong = GrayImage::new(100, 100);
        assert!(matches!(pipeline.process(&wrong, &right), Err(PipelineError::WrongSize { .. })));
    }

    #[test]
    fn a_right_camera_two_rows_low_is_found_and_matched_as_if_aligned() {
        // Squares of several sizes across the image, the right view 12 px
        // to the left and two rows down.
        let at: Vec<(u32, u32, u32)> =
            (0..24).map(|k| (30 + (k % 8) * 45, 30 + (k / 8) * 60, 14 + (k * 7) % 11)).collect();
        let camera = StereoCamera { width_px: 420, height_px: 240, ..StereoCamera::default() };
        let left = squares(420, 240, &at, 0);
        let aligned = squares(420, 240, &at, 12);
        let low = crate::perturb::shift_down(&aligned, 2);
        let pipeline = StereoPipeline::new(camera, FeatureConfig::default());
        let (expected, report) = pipeline.process_pair(&left, &aligned).unwrap();
        assert_eq!(report.applied_row_offset, 0);
        assert!(report.row_offset_px.unwrap().abs() < 0.2, "{report:?}");
        let pipeline = StereoPipeline::new(camera, FeatureConfig::default());
        let (landmarks, report) = pipeline.process_pair(&left, &low).unwrap();
        assert_eq!(report.applied_row_offset, 2, "{report:?}");
        assert!((report.row_offset_px.unwrap() - 2.0).abs() < 0.2, "{report:?}");
        assert!((pipeline.row_offset().unwrap() - 2.0).abs() < 0.2);
        assert!(
            landmarks.len() + 2 >= expected.len() && landmarks.len() >= 24,
            "{} of {}",
            landmarks.len(),
            expected.len()
        );
        for l in &landmarks {
            assert!((l.pixels.disparity() - 12.0).abs() < 0.05, "{:?}", l.pixels);
        }
        // Without the estimate, two rows are beyond the matcher's tolerance
        // and the blocks compared are two rows apart.
        let blind = StereoPipeline::new(camera, FeatureConfig { max_row_offset_px: 0, ..FeatureConfig::default() });
        let blind = blind.process(&left, &low).unwrap();
        let good = blind.iter().filter(|l| (l.pixels.disparity() - 12.0).abs() < 0.05).count();
        assert!(good < expected.len() / 2, "{good} of {}", blind.len());
    }

    /// A smooth texture, and the right camera's view of it: `shift` px
    /// of disparity, `gain` and `offset` of exposure.
    fn textured_pair(shift: f64, gain: f64, offset: f64) -> (GrayImage, GrayImage) {
        let g = |x: f64, y: f64| 120.0 + 50.0 * (0.31 * x + 0.23 * y).sin() + 35.0 * (0.17 * x - 0.29 * y).cos();
        let left = GrayImage::from_fn(160, 60, |x, y| Luma([g(f64::from(x), f64::from(y)).round() as u8]));
        let right = GrayImage::from_fn(160, 60, |x, y| {
            Luma([(gain * g(f64::from(x) + shift, f64::from(y)) + offset).round().clamp(0.0, 255.0) as u8])
        });
        (left, right)
    }

    #[test]
    fn sub_pixel_disparity_survives_a_different_exposure_in_each_camera() {
        for (gain, offset) in [(1.0, 0.0), (0.6, 0.0), (0.6, 25.0), (1.3, -20.0)] {
            let (left, right) = textured_pair(9.4, gain, offset);
            let exposure = Exposure::between(&left, &right);
            assert!((f64::from(exposure.gain) * gain - 1.0).abs() < 0.05, "{exposure:?} for gain {gain}");
            let mut errors: Vec<f64> = (20..140)
                .step_by(7)
                .flat_map(|x| [15, 30, 45].map(|y| (x, y)))
                .filter_map(|(x, y)| refine_disparity(&left, &right, exposure, x, x - 9, y, 0))
                .map(|d| (d - 9.4).abs())
                .collect();
            errors.sort_by(f64::total_cmp);
            let median = errors[errors.len() / 2];
            assert!(median < 0.1, "gain {gain}, offset {offset}: median error {median:.3} px");
            // Without the correction, a different exposure biases it.
            let ignored = Exposure { gain: 1.0, offset: 0.0 };
            if gain != 1.0 {
                let off = (20..140)
                    .step_by(7)
                    .filter_map(|x| refine_disparity(&left, &right, ignored, x, x - 9, 30, 0))
                    .filter(|d| (d - 9.4).abs() > 0.3)
                    .count();
                assert!(off > 3, "gain {gain}: only {off} biased");
            }
        }
    }

    #[test]
    fn the_ratio_test_drops_ambiguous_matches() {
        let d = |bits: u64| Descriptor([bits, 0, 0, 0]);
        let f = |x, descriptor| Feature { x, y: 10, score: 1, descriptor };
        let left = [f(100, d(0b1111))];
        // Two right candidates one bit apart: ambiguous.
        let right = [f(90, d(0b1110)), f(80, d(0b0111))];
        assert!(match_stereo(&left, &right, &FeatureConfig::default()).is_empty());
        // One clearly nearer: kept.
        let right = [f(90, d(0b1111)), f(80, d(u64::MAX))];
        assert_eq!(match_stereo(&left, &right, &FeatureConfig::default()), [(0, 0)]);
        // Out of the disparity range: none.
        let right = [f(101, d(0b1111))];
        assert!(match_stereo(&left, &right, &FeatureConfig::default()).is_empty());
    }
}
