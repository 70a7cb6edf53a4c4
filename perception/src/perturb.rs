//! What real cameras do to a stereo pair that a rectified benchmark does
//! not: a right camera a row or two out of line, blur, low contrast. Each
//! perturbation is a pure function of the image, computed the same way on
//! every machine, so a test can build perturbed copies of a sequence and
//! hold the pipeline's accuracy on them.

use image::GrayImage;
use std::path::Path;

/// One way of spoiling a stereo pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Perturbation {
    /// The right image's content moved down this many rows (the top rows
    /// repeat the first): a vertical misalignment of the rig.
    ShiftRight(u32),
    /// Both images blurred by a Gaussian of this σ, px.
    Blur(f64),
    /// Both images' contrast about their own mean grey level scaled by
    /// this factor.
    Contrast(f64),
}

impl Perturbation {
    /// The pair as the perturbed cameras would have given it.
    pub fn apply(&self, left: &GrayImage, right: &GrayImage) -> (GrayImage, GrayImage) {
        match *self {
            Perturbation::ShiftRight(rows) => (left.clone(), shift_down(right, rows)),
            Perturbation::Blur(sigma) => (gaussian_blur(left, sigma), gaussian_blur(right, sigma)),
            Perturbation::Contrast(factor) => (scale_contrast(left, factor), scale_contrast(right, factor)),
        }
    }

    /// A short name for tables and directories: `shift-1`, `blur-2`,
    /// `contrast-0.5`.
    pub fn name(&self) -> String {
        match self {
            Perturbation::ShiftRight(rows) => format!("shift-{rows}"),
            Perturbation::Blur(sigma) => format!("blur-{sigma}"),
            Perturbation::Contrast(factor) => format!("contrast-{factor}"),
        }
    }
}

/// `image` with its content moved down `rows` rows; the rows uncovered at
/// the top repeat the first row.
pub fn shift_down(image: &GrayImage, rows: u32) -> GrayImage {
    GrayImage::from_fn(image.width(), image.height(), |x, y| *image.get_pixel(x, y.saturating_sub(rows)))
}

/// `image` convolved with a Gaussian of standard deviation `sigma` px
/// (kernel out to 3σ, normalised, borders clamped), rounded to grey levels.
/// A σ of zero or less leaves it as it is.
pub fn gaussian_blur(image: &GrayImage, sigma: f64) -> GrayImage {
    if sigma <= 0.0 {
        return image.clone();
    }
    let radius = (3.0 * sigma).ceil() as i64;
    let mut kernel: Vec<f64> = (-radius..=radius).map(|k| (-((k * k) as f64) / (2.0 * sigma * sigma)).exp()).collect();
    let total: f64 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= total);
    let (w, h) = (i64::from(image.width()), i64::from(image.height()));
    let src = image.as_raw();
    let clamp = |v: i64, n: i64| v.clamp(0, n - 1) as usize;
    let mut rows = vec![0.0f64; src.len()];
    for y in 0..h {
        for x in 0..w {
            rows[(y * w + x) as usize] = kernel
                .iter()
                .zip(-radius..=radius)
                .map(|(k, dx)| k * f64::from(src[(y * w) as usize + clamp(x + dx, w)]))
                .sum();
        }
    }
    let mut out = vec![0u8; src.len()];
    for y in 0..h {
        for x in 0..w {
            let v: f64 = kernel
                .iter()
                .zip(-radius..=radius)
                .map(|(k, dy)| k * rows[clamp(y + dy, h) * w as usize + x as usize])
                .sum();
            out[(y * w + x) as usize] = v.round().clamp(0.0, 255.0) as u8;
        }
    }
    GrayImage::from_raw(image.width(), image.height(), out).expect("same size")
}

/// `image` with its contrast about its mean grey level scaled by `factor`,
/// rounded and clamped to grey levels.
pub fn scale_contrast(image: &GrayImage, factor: f64) -> GrayImage {
    let raw = image.as_raw();
    let mean = raw.iter().map(|&p| f64::from(p)).sum::<f64>() / raw.len().max(1) as f64;
    let out = raw.iter().map(|&p| (mean + factor * (f64::from(p) - mean)).round().clamp(0.0, 255.0) as u8).collect();
    GrayImage::from_raw(image.width(), image.height(), out).expect("same size")
}

/// Writes a copy of the KITTI sequence in `from` to `to` with every pair
/// perturbed: the same `calib.txt`, `times.txt` and `poses.txt` (if there
/// is one), and `image_0/`, `image_1/` as PNGs. The first `frames` pairs
/// only, if given.
pub fn perturb_sequence(
    from: &Path,
    to: &Path,
    perturbation: Perturbation,
    frames: Option<usize>,
) -> Result<(), String> {
    fn io(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
        move |e| format!("{}: {e}", path.display())
    }
    let times = ubf_core::config::read_text_bounded(&from.join("times.txt"), ubf_core::config::MOST_SETTINGS_BYTES)
        .map_err(io(&from.join("times.txt")))?;
    let count = times.lines().filter(|l| !l.trim().is_empty()).count().min(frames.unwrap_or(usize::MAX));
    for dir in ["image_0", "image_1"] {
        std::fs::create_dir_all(to.join(dir)).map_err(io(&to.join(dir)))?;
    }
    let keep = |text: &str| {
        text.lines().filter(|l| !l.trim().is_empty()).take(count).map(|l| format!("{l}\n")).collect::<String>()
    };
    std::fs::write(to.join("times.txt"), keep(&times)).map_err(io(&to.join("times.txt")))?;
    std::fs::copy(from.join("calib.txt"), to.join("calib.txt")).map_err(io(&from.join("calib.txt")))?;
    let poses = from.join("poses.txt");
    if poses.is_file() {
        let text =
            ubf_core::config::read_text_bounded(&poses, ubf_core::config::MOST_SETTINGS_BYTES).map_err(io(&poses))?;
        std::fs::write(to.join("poses.txt"), keep(&text)).map_err(io(&to.join("poses.txt")))?;
    }
    for i in 0..count {
        let name = format!("{i:06}.png");
        let load = |dir: &str| {
            let path = from.join(dir).join(&name);
            crate::source::read_grey(&path).map_err(|e| e.to_string())
        };
        let (left, right) = perturbation.apply(&load("image_0")?, &load("image_1")?);
        for (dir, image) in [("image_0", left), ("image_1", right)] {
            let path = to.join(dir).join(&name);
            image.save(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn each_perturbation_does_what_it_says() {
        let image = GrayImage::from_fn(40, 30, |x, y| Luma([((x * 5 + y * 3) % 200) as u8 + 20]));
        let shifted = shift_down(&image, 2);
        assert_eq!(shifted.get_pixel(7, 12), image.get_pixel(7, 10));
        assert_eq!(shifted.get_pixel(7, 0), image.get_pixel(7, 0));
        // A blur keeps a flat image flat and the mean of a textured one.
        let flat = GrayImage::from_pixel(20, 20, Luma([77]));
        assert_eq!(gaussian_blur(&flat, 2.0), flat);
        let mean = |i: &GrayImage| i.as_raw().iter().map(|&p| f64::from(p)).sum::<f64>() / i.as_raw().len() as f64;
        let blurred = gaussian_blur(&image, 1.5);
        assert!((mean(&blurred) - mean(&image)).abs() < 3.0);
        let spread = |i: &GrayImage| i.as_raw().iter().map(|&p| (f64::from(p) - mean(i)).powi(2)).sum::<f64>();
        assert!(spread(&blurred) < spread(&image));
        // Half the contrast: half the spread of grey levels, give or take
        // rounding, about the same mean.
        let low = scale_contrast(&image, 0.5);
        assert!((mean(&low) - mean(&image)).abs() < 0.6);
        assert!((spread(&low) / spread(&image) - 0.25).abs() < 0.01);
        // The right image only is shifted.
        let (l, r) = Perturbation::ShiftRight(1).apply(&image, &image);
        assert_eq!((l == image, r == image), (true, false));
    }
}
