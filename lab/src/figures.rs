//! The research's figures: the error model's heat map (thesis figure 16)
//! and the map of where action aiding pays.

use crate::environment_map::EnvironmentMap;
use plotters::prelude::*;
use std::path::Path;
use ubf_session::plot::{canvas, equal_scale, wrap_text, PlotError};

/// Draws the CV of `cv` over the floor ahead of the camera as a heat map
/// (thesis figure 16): lateral position across, depth up, log₁₀ CV as
/// colour from blue (best) to red (worst); outside the stereo field of view
/// is left white.
pub fn draw_error_model(
    title: &str,
    cv: impl Fn(f64, f64) -> f64,
    camera: &ubf_perception::StereoCamera,
    max_depth: f64,
    path: &Path,
) -> Result<(), PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError::new(path, e);
    let half_fov = camera.horizontal_fov() / 2.0;
    let x_max = max_depth * half_fov.tan();
    let root = canvas(path, (1000, 900))?;
    let root = root.margin(8, 0, 0, 0).titled(title, ("sans-serif", 22)).map_err(|e| fail(&e))?;
    let (map_area, bar_area) = root.split_horizontally(890);
    let chart_on = |x: std::ops::Range<f64>, y: std::ops::Range<f64>| {
        ChartBuilder::on(&map_area).margin(12).x_label_area_size(36).y_label_area_size(50).build_cartesian_2d(x, y)
    };
    // A metre as long across as in depth, so the field of view has its
    // true angle.
    let pixels = chart_on(0.0..1.0, 0.0..1.0).map_err(|e| fail(&e))?.plotting_area().dim_in_pixel();
    let (x_range, y_range) = equal_scale((-x_max, x_max, 0.0, max_depth), pixels);
    let mut chart = chart_on(x_range, y_range).map_err(|e| fail(&e))?;
    chart
        .configure_mesh()
        .x_desc("lateral x (m, right positive)")
        .y_desc("depth y (m)")
        .light_line_style(WHITE)
        .draw()
        .map_err(|e| fail(&e))?;
    let cell = max_depth / 150.0;
    let inside = |x: f64, y: f64| x.abs() + camera.baseline_m / 2.0 <= y * half_fov.tan() && y > 1.0;
    let mut cells = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = cell / 2.0;
    while y < max_depth {
        let mut x = -x_max + cell / 2.0;
        while x < x_max {
            if inside(x, y) {
                let v = cv(x, y).log10();
                (lo, hi) = (lo.min(v), hi.max(v));
                cells.push((x, y, v));
            }
            x += cell;
        }
        y += cell;
    }
    let colour = |v: f64| {
        let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
        // Blue (low CV, good) through white-ish to red (high CV, poor).
        let (r, g, b) = if t < 0.5 {
            let u = t * 2.0;
            (40.0 + 200.0 * u, 80.0 + 160.0 * u, 220.0 + 20.0 * u)
        } else {
            let u = (t - 0.5) * 2.0;
            (240.0, 240.0 - 190.0 * u, 240.0 - 200.0 * u)
        };
        RGBColor(r as u8, g as u8, b as u8)
    };
    chart
        .draw_series(cells.iter().map(|&(x, y, v)| {
            Rectangle::new([(x - cell / 2.0, y - cell / 2.0), (x + cell / 2.0, y + cell / 2.0)], colour(v).filled())
        }))
        .map_err(|e| fail(&e))?;
    let edge = ShapeStyle::from(&BLACK).stroke_width(1);
    for side in [-1.0, 1.0] {
        let top = (side * (max_depth * half_fov.tan() - camera.baseline_m / 2.0), max_depth);
        // Both images overlap from the depth where |x| + T/2 = y·tan(fov/2).
        let apex = (0.0, camera.baseline_m / 2.0 / half_fov.tan());
        chart.draw_series([PathElement::new(vec![apex, top], edge)]).map_err(|e| fail(&e))?;
    }
    // The colour bar: what each colour means, on the same log scale.
    let (lo_bar, hi_bar) = if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) };
    let mut bar = ChartBuilder::on(&bar_area)
        .margin_top(12)
        .margin_bottom(48)
        .margin_right(14)
        .y_label_area_size(62)
        .build_cartesian_2d(0.0..1.0, lo_bar..hi_bar)
        .map_err(|e| fail(&e))?;
    bar.configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .disable_y_mesh()
        .y_desc("log10 CV")
        .y_label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .y_label_formatter(&|v| format!("{v:.1}"))
        .draw()
        .map_err(|e| fail(&e))?;
    let steps = 100;
    let step = (hi_bar - lo_bar) / f64::from(steps);
    bar.draw_series((0..steps).map(|i| {
        let v = lo_bar + step * f64::from(i);
        Rectangle::new([(0.0, v), (1.0, v + step)], colour(v + step / 2.0).filled())
    }))
    .map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

/// Draws the environment map: one row per factor, one cell per level,
/// coloured by the held-out ratio of the best aided technique's end-point
/// error to straight driving's (green where aiding pays, red where it
/// costs), each cell labelled with the technique, the ratio and its 95 %
/// interval; the base route's cells are outlined.
pub fn draw_environment_map(map: &EnvironmentMap, path: &Path) -> Result<(), PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError::new(path, e);
    let mut factors: Vec<&str> = Vec::new();
    for c in &map.cells {
        if !factors.contains(&c.factor) {
            factors.push(c.factor);
        }
    }
    let columns = factors.iter().map(|f| map.cells.iter().filter(|c| c.factor == *f).count()).max().unwrap_or(1);
    let (label_w, cell_w, cell_h, top) = (190i32, 190i32, 84i32, 70i32);
    let width = (label_w + cell_w * columns as i32 + 20) as u32;
    let note = "Each cell: the level, the aided technique with the least error on the development seeds, and its \
                error over straight driving's on held-out runs with 95 % CI. Green: aiding pays; red: it costs. \
                Outlined: the base route.";
    let note_lines = wrap_text(note, 13.0, width - 24);
    let (key_h, line_h) = (58i32, 18i32);
    let bottom = 16 + key_h + line_h * note_lines.len() as i32 + 8;
    let height = (top + cell_h * factors.len() as i32 + bottom) as u32;
    let root = canvas(path, (width, height))?;
    let title = format!(
        "Where aiding pays: best aided / straight end-point error (held-out seeds {}..{}, layout {})",
        map.held_out_seeds[0], map.held_out_seeds[1], map.held_out_layout_seed
    );
    root.draw(&Text::new(title, (12, 14), ("sans-serif", 18))).map_err(|e| fail(&e))?;
    // Green below 1, red above, saturating at a factor of 2 either way.
    let colour = |ratio: f64| {
        let t = (ratio.max(1e-3).log2()).clamp(-1.0, 1.0);
        let (r, g, b) = if t < 0.0 {
            let u = -t;
            (255.0 - 155.0 * u, 255.0 - 55.0 * u, 255.0 - 155.0 * u)
        } else {
            (255.0 - 15.0 * t, 255.0 - 155.0 * t, 255.0 - 155.0 * t)
        };
        RGBColor(r as u8, g as u8, b as u8)
    };
    for (row, factor) in factors.iter().enumerate() {
        let y = top + cell_h * row as i32;
        root.draw(&Text::new(factor.to_string(), (12, y + cell_h / 2 - 8), ("sans-serif", 16)))
            .map_err(|e| fail(&e))?;
        for (col, cell) in map.cells.iter().filter(|c| c.factor == *factor).enumerate() {
            let x = label_w + cell_w * col as i32;
            let corners = [(x + 2, y + 2), (x + cell_w - 2, y + cell_h - 2)];
            root.draw(&Rectangle::new(corners, colour(cell.ratio).filled())).map_err(|e| fail(&e))?;
            let edge = if cell.base { BLACK.stroke_width(3) } else { RGBColor(180, 180, 180).stroke_width(1) };
            root.draw(&Rectangle::new(corners, edge)).map_err(|e| fail(&e))?;
            let lines = [
                format!("{}: {}", cell.level, cell.best),
                format!("× {:.2}", cell.ratio),
                format!("[{:.2}, {:.2}]", cell.ratio_ci95[0], cell.ratio_ci95[1]),
            ];
            for (k, line) in lines.iter().enumerate() {
                let at = (x + 10, y + 8 + 24 * k as i32);
                root.draw(&Text::new(line.clone(), at, ("sans-serif", 15))).map_err(|e| fail(&e))?;
            }
        }
    }
    // The colour key: the ratio each colour stands for, on the cells' scale.
    let key_top = top + cell_h * factors.len() as i32 + 16;
    root.draw(&Text::new("aided / straight", (12, key_top + 2), ("sans-serif", 15))).map_err(|e| fail(&e))?;
    let (key_left, key_w) = (label_w, 400i32);
    for i in 0..key_w {
        let ratio = 2f64.powf(2.0 * f64::from(i) / f64::from(key_w) - 1.0);
        let column = [(key_left + i, key_top), (key_left + i + 1, key_top + 18)];
        root.draw(&Rectangle::new(column, colour(ratio).filled())).map_err(|e| fail(&e))?;
    }
    root.draw(&Rectangle::new([(key_left, key_top), (key_left + key_w, key_top + 18)], BLACK.stroke_width(1)))
        .map_err(|e| fail(&e))?;
    for (ratio, label) in [(0.5, "× 0.5 or less"), (1.0, "× 1"), (2.0, "× 2 or more")] {
        let x = key_left + (f64::log2(ratio) + 1.0) as i32 * key_w / 2;
        root.draw(&PathElement::new(vec![(x, key_top + 18), (x, key_top + 24)], BLACK.stroke_width(1)))
            .map_err(|e| fail(&e))?;
        let anchor = match ratio {
            r if r < 1.0 => (x, key_top + 28),
            r if r > 1.0 => (x - ubf_session::plot::text_width(label, 13.0) as i32, key_top + 28),
            _ => (x - ubf_session::plot::text_width(label, 13.0) as i32 / 2, key_top + 28),
        };
        root.draw(&Text::new(label, anchor, ("sans-serif", 13))).map_err(|e| fail(&e))?;
    }
    for (k, line) in note_lines.iter().enumerate() {
        let at = (12, key_top + key_h + line_h * k as i32);
        root.draw(&Text::new(line.as_str(), at, ("sans-serif", 13))).map_err(|e| fail(&e))?;
    }
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment_map::EnvironmentCell;

    /// Whether any pixel of `png` within `margin` pixels of an edge is dark:
    /// text or lines running off the canvas.
    fn ink_at_the_edges(png: &Path, margin: u32) -> bool {
        let image = image::open(png).unwrap().to_luma8();
        let (w, h) = image.dimensions();
        image.enumerate_pixels().any(|(x, y, p)| {
            let near_edge = x < margin || y < margin || x >= w - margin || y >= h - margin;
            near_edge && p.0[0] < 128
        })
    }

    #[test]
    fn the_environment_map_keeps_its_text_and_key_on_the_canvas() {
        let factors = ["corridor width", "landmarks", "side-wall share", "featureless stretch"];
        let cells = factors
            .iter()
            .flat_map(|&factor| {
                [0.4, 0.9, 1.0, 2.6].into_iter().enumerate().map(move |(i, ratio)| EnvironmentCell {
                    factor,
                    level: format!("{} m", 10 * i),
                    base: i == 2,
                    best: "tracking",
                    straight_m: 0.1,
                    aided_m: 0.1 * ratio,
                    ratio,
                    ratio_ci95: [ratio * 0.8, ratio * 1.25],
                })
            })
            .collect();
        let map = EnvironmentMap {
            development_seeds: [0, 30],
            held_out_seeds: [1000, 1030],
            held_out_layout_seed: 101,
            cells,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.png");
        draw_environment_map(&map, &path).unwrap();
        assert!(!ink_at_the_edges(&path, 4), "something runs off the canvas");
    }

    #[test]
    fn the_error_model_keeps_its_labels_on_the_canvas() {
        let camera = ubf_perception::StereoCamera::default();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.png");
        draw_error_model("model", |x, y| 0.01 + x.abs() / y, &camera, 40.0, &path).unwrap();
        assert_eq!(image::image_dimensions(&path).unwrap(), (1000, 900));
        assert!(!ink_at_the_edges(&path, 2), "something runs off the canvas");
    }
}
