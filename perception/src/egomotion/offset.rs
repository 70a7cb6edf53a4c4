//! The stereo rig's disparity offset, read from one step's landmarks.
//!
//! A rectification that leaves every disparity short by a fraction of a
//! pixel δ inflates each depth by about δ / d: far landmarks (small
//! disparity d) by more than near ones. Near and far landmarks then
//! disagree on how far the robot moved, and one δ makes them agree. The
//! step's motion and δ are fitted together to the pixels the landmarks
//! were seen at, each landmark's position fitted with them (a two-view
//! bundle adjustment): a least-squares fit to the triangulated points
//! instead, the estimator's own cost, is biased by the pixel noise itself
//! (a far point's depth error is skewed, and the noisy points stand in the
//! fit's Jacobian), and on a synthetic drive with 0.2 px of noise it read
//! an offset of 0.4–0.9 px where there was none. In pixels the noise is
//! what the model assumes, and the bias is gone to within the test's
//! tolerance (`the_disparity_offset_is_read_…` in `tracker.rs`).

use super::step::{Mounts, Pair, PlanarMotion};
use crate::stereo::StereoCamera;
use nalgebra::{Matrix2, Matrix2x4, Matrix4, Matrix4x2, Vector2, Vector4};
use ubf_core::StereoPixels;

/// One step's reading of the disparity offset: the pixels to add to every
/// disparity, beyond the offset the landmarks were triangulated with, that
/// make the step's landmarks fit one motion best.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct OffsetReading {
    /// The offset, px.
    pub(super) px: f64,
    /// Its variance, px².
    pub(super) variance: f64,
}

/// A landmark as the fit holds it, in the earlier frame's camera: its line
/// of sight from the left camera (`alpha` across, `beta` up, per metre of
/// depth) and its inverse depth `rho`, 1/m. Inverse depth keeps a far
/// landmark's pixels close to linear in it. `beta` is kept as seen: on a
/// level rig, a planar motion moves no column with a landmark's height.
#[derive(Clone, Copy, Debug)]
struct Landmark {
    alpha: f64,
    beta: f64,
    rho: f64,
}

/// The columns a landmark is predicted at, left and right before, left and
/// right after, for the planar motion `(tx, ty, yaw)` and the extra offset
/// `δ` in `g`: the point is moved by the motion (`a = R b + t` between the
/// robot frames, each camera lifted by its mount) and projected by a
/// camera whose offset is `camera`'s plus `δ`.
fn predict(camera: &StereoCamera, mounts: &Mounts, g: &Vector4<f64>, l: &Landmark) -> Option<Vector4<f64>> {
    let camera = StereoCamera { disparity_offset_px: camera.disparity_offset_px + g[3], ..*camera };
    let depth = 1.0 / l.rho;
    let point = [-camera.baseline_m / 2.0 + l.alpha * depth, depth, l.beta * depth];
    let before = camera.project(point)?;
    let a = mounts.before.cam_to_robot(point);
    let (s, c) = g[2].sin_cos();
    let (dx, dy) = (a[0] - g[0], a[1] - g[1]);
    let b = [c * dx + s * dy, -s * dx + c * dy, a[2]];
    let after = camera.project(mounts.after.robot_to_cam(b))?;
    Some(Vector4::new(before.u_left, before.u_right, after.u_left, after.u_right))
}

/// One landmark's share of the normal equations: the inverse of its own
/// 2 × 2 information, its coupling to the motion and offset, its gradient.
type Share = (Matrix2<f64>, Matrix2x4<f64>, Vector2<f64>);

/// Pixel columns seen, before and after, in the order [`predict`] gives.
fn columns(pixels: &[StereoPixels; 2]) -> Vector4<f64> {
    Vector4::new(pixels[0].u_left, pixels[0].u_right, pixels[1].u_left, pixels[1].u_right)
}

/// What one step's consistent landmarks `pairs` say of the disparity
/// offset beyond `camera`'s (the camera the landmarks were triangulated
/// with), starting from the step's `motion`; `mounts` lift each frame's
/// camera onto the robot, and `pixel_sigma` is the column noise assumed.
///
/// Gauss–Newton on the columns' residuals over the motion, δ and each
/// landmark's line and inverse depth; each landmark's two unknowns are
/// eliminated (Schur complement), so an iteration costs a few 2 × 2 and one
/// 4 × 4 solve per landmark set. The variance is the inverse information's,
/// scaled up when the residuals are larger than `pixel_sigma` explains.
/// `None` with fewer than five landmarks with pixels, or a fit that does
/// not converge to a finite reading.
pub(super) fn read(
    camera: &StereoCamera,
    mounts: &Mounts,
    pairs: &[Pair],
    motion: &PlanarMotion,
    pixel_sigma: f64,
) -> Option<OffsetReading> {
    let seen: Vec<(Vector4<f64>, Landmark)> = pairs
        .iter()
        .filter_map(|p| {
            let pixels = p.pixels?;
            let point = camera.triangulate(&pixels[0])?;
            let depth = point[1];
            let alpha = (point[0] + camera.baseline_m / 2.0) / depth;
            Some((columns(&pixels), Landmark { alpha, beta: point[2] / depth, rho: 1.0 / depth }))
        })
        .collect();
    if seen.len() < 5 {
        return None;
    }
    let (observed, mut landmarks): (Vec<Vector4<f64>>, Vec<Landmark>) = seen.into_iter().unzip();
    let mut g = Vector4::new(motion.forward, motion.left, motion.yaw, 0.0);
    // Finite-difference steps for the motion and the offset: a micrometre,
    // a microradian, a millionth of a pixel (and for a landmark, 10⁻⁷ of
    // its line's slope and a millionth of its inverse depth): far below
    // what moves a column by the noise, far above rounding.
    const STEPS: [f64; 4] = [1e-6, 1e-6, 1e-6, 1e-6];
    let mut information = Matrix4::zeros();
    let mut cost = 0.0;
    let mut shares: Vec<Option<Share>> = vec![None; landmarks.len()];
    for iteration in 0..8 {
        let (mut reduced, mut gradient) = (Matrix4::zeros(), Vector4::zeros());
        cost = 0.0;
        for ((seen, l), share) in observed.iter().zip(&landmarks).zip(&mut shares) {
            *share = None;
            let Some(predicted) = predict(camera, mounts, &g, l) else { continue };
            let r = (predicted - seen) / pixel_sigma;
            let mut j_global = Matrix4::zeros();
            for k in 0..4 {
                let mut moved = g;
                moved[k] += STEPS[k];
                let Some(p) = predict(camera, mounts, &moved, l) else { continue };
                j_global.set_column(k, &((p - predicted) / (STEPS[k] * pixel_sigma)));
            }
            let mut j_own = Matrix4x2::zeros();
            let steps = [1e-7, 1e-6 * l.rho];
            for (k, step) in steps.into_iter().enumerate() {
                let mut moved = *l;
                if k == 0 {
                    moved.alpha += step;
                } else {
                    moved.rho += step;
                }
                let Some(p) = predict(camera, mounts, &g, &moved) else { continue };
                j_own.set_column(k, &((p - predicted) / (step * pixel_sigma)));
            }
            let own = j_own.transpose() * j_own;
            let Some(own_inverse) = own.try_inverse() else { continue };
            let coupling = j_own.transpose() * j_global;
            let own_gradient = j_own.transpose() * r;
            reduced += j_global.transpose() * j_global - coupling.transpose() * own_inverse * coupling;
            gradient += j_global.transpose() * r - coupling.transpose() * own_inverse * own_gradient;
            cost += r.norm_squared();
            *share = Some((own_inverse, coupling, own_gradient));
        }
        information = reduced;
        let step = reduced.lu().solve(&(-gradient))?;
        g += step;
        for (l, share) in landmarks.iter_mut().zip(&shares) {
            let Some((own_inverse, coupling, own_gradient)) = share else { continue };
            let own_step = -(own_inverse * (own_gradient + coupling * step));
            l.alpha += own_step[0];
            // A step through infinity is halved towards it instead.
            l.rho = if l.rho + own_step[1] > 0.0 { l.rho + own_step[1] } else { l.rho / 2.0 };
        }
        if step.norm() < 1e-7 || iteration == 7 {
            break;
        }
    }
    let used = shares.iter().filter(|s| s.is_some()).count();
    if used < 5 {
        return None;
    }
    // Four columns per landmark, two unknowns per landmark, four globals.
    let dof = (2 * used - 4) as f64;
    let variance = information.try_inverse()?[(3, 3)] * (cost / dof).max(1.0);
    (g[3].is_finite() && variance.is_finite() && variance > 0.0).then_some(OffsetReading { px: g[3], variance })
}
