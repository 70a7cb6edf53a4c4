//! `plot.png`: the world and the run seen from above, as in the thesis's
//! figure 31: walls, landmarks, the true and the estimated paths, and the
//! points where the robot changed its mind.

use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;
use ubf_core::Goal;
use ubf_robots::sim::{Anchor, World};

/// What a run plot shows.
pub struct RunPlot<'a> {
    /// The caption.
    pub title: &'a str,
    /// Walls, boxes, landmarks, people.
    pub world: &'a World,
    /// Where the robot really went.
    pub true_path: &'a [(f64, f64)],
    /// Where it believed it went.
    pub estimated_path: &'a [(f64, f64)],
    /// Where the winning behaviour changed, on the true path.
    pub decisions: &'a [(f64, f64)],
    /// The goal.
    pub goal: Option<Goal>,
}

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("drawing {path}: {message}")]
pub struct PlotError {
    path: String,
    message: String,
}

static FONT: Once = Once::new();

/// The font ships inside a crate, so plots need no system font libraries.
fn register_font() {
    FONT.call_once(|| {
        // Registering a valid built-in font cannot fail; if it somehow did,
        // text would be missing, not the plot.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

fn bounds(plot: &RunPlot) -> (f64, f64, f64, f64) {
    let mut points: Vec<(f64, f64)> = plot.true_path.iter().chain(plot.estimated_path).copied().collect();
    for s in &plot.world.segments {
        points.extend([s.a, s.b]);
    }
    for lm in &plot.world.landmarks {
        let (p, _) = plot.world.landmark_at(lm, 0.0);
        points.push((p[0], p[1]));
    }
    if let Some(g) = plot.goal {
        points.push((g.x, g.y));
    }
    let finite = points.into_iter().filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in finite {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !x0.is_finite() {
        return (-1.0, 1.0, -1.0, 1.0);
    }
    let margin = 0.05 * (x1 - x0).max(y1 - y0).max(1.0);
    (x0 - margin, x1 + margin, y0 - margin, y1 + margin)
}

/// Draws the plot into a PNG at `path`.
pub fn draw(plot: &RunPlot, path: &Path) -> Result<(), PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError { path: path.display().to_string(), message: e.to_string() };
    register_font();
    let (x0, x1, y0, y1) = bounds(plot);
    // Equal scales on both axes, so a corridor looks like one.
    let width = 1400u32;
    let plot_width = f64::from(width - 90);
    let height = ((plot_width * (y1 - y0) / (x1 - x0)) as u32 + 110).clamp(260, 1400);
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(plot.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| fail(&e))?;
    chart.configure_mesh().x_desc("x (m)").y_desc("y (m)").light_line_style(WHITE).draw().map_err(|e| fail(&e))?;

    let wall = ShapeStyle::from(&BLACK).stroke_width(2);
    chart
        .draw_series(plot.world.segments.iter().map(|s| PathElement::new(vec![s.a, s.b], wall)))
        .map_err(|e| fail(&e))?;
    // Only what the plot shows goes in the legend.
    let landmark_style = ShapeStyle::from(&RED).filled();
    let fixed: Vec<(f64, f64)> = plot
        .world
        .landmarks
        .iter()
        .filter_map(|lm| match lm.anchor {
            Anchor::Fixed { position, .. } => Some((position[0], position[1])),
            Anchor::Person { .. } => None,
        })
        .collect();
    if !fixed.is_empty() {
        chart
            .draw_series(fixed.iter().map(|&p| Circle::new(p, 4, landmark_style)))
            .map_err(|e| fail(&e))?
            .label("landmark")
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, landmark_style));
    }
    let person_style = ShapeStyle::from(&RGBColor(230, 140, 0)).stroke_width(2);
    if !plot.world.people.is_empty() {
        chart
            .draw_series(
                (0..plot.world.people.len()).map(|i| Circle::new(plot.world.person_position(i, 0.0), 6, person_style)),
            )
            .map_err(|e| fail(&e))?
            .label("person (at the start)")
            .legend(move |(x, y)| Circle::new((x + 10, y), 6, person_style));
    }

    let truth = RGBColor(30, 80, 200);
    let estimate = RGBColor(20, 150, 60);
    if !plot.true_path.is_empty() {
        chart
            .draw_series(LineSeries::new(plot.true_path.iter().copied(), truth.stroke_width(2)))
            .map_err(|e| fail(&e))?
            .label("true path")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], truth.stroke_width(2)));
    }
    if !plot.estimated_path.is_empty() {
        chart
            .draw_series(LineSeries::new(plot.estimated_path.iter().copied(), estimate.stroke_width(1)))
            .map_err(|e| fail(&e))?
            .label("estimated path")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], estimate.stroke_width(1)));
    }
    if !plot.decisions.is_empty() {
        chart
            .draw_series(plot.decisions.iter().map(|&p| Cross::new(p, 5, truth.stroke_width(2))))
            .map_err(|e| fail(&e))?
            .label("decision point")
            .legend(move |(x, y)| Cross::new((x + 10, y), 5, truth.stroke_width(2)));
    }
    if let Some(g) = plot.goal {
        let goal_style = ShapeStyle::from(&BLACK).stroke_width(2);
        chart
            .draw_series([TriangleMarker::new((g.x, g.y), 8, goal_style)])
            .map_err(|e| fail(&e))?
            .label("goal")
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 8, goal_style));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.85))
        .draw()
        .map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

/// Draws a replayed sequence's egomotion path over the true one (when
/// there is one), from above: x ahead of the first pose, y to its left.
pub fn draw_paths(
    estimate: &[ubf_core::Pose2],
    truth: Option<&[ubf_core::Pose2]>,
    path: &Path,
) -> Result<(), PlotError> {
    let world = World {
        segments: Vec::new(),
        landmarks: Vec::new(),
        people: Vec::new(),
        corridor: None,
        featureless: Vec::new(),
    };
    let points = |poses: &[ubf_core::Pose2]| poses.iter().map(|p| (p.x, p.y)).collect::<Vec<_>>();
    let estimated_path = points(estimate);
    let true_path = truth.map(points).unwrap_or_default();
    let title = if truth.is_some() { "egomotion over the ground truth, from above" } else { "egomotion, from above" };
    let plot = RunPlot {
        title,
        world: &world,
        true_path: &true_path,
        estimated_path: &estimated_path,
        decisions: &[],
        goal: None,
    };
    draw(&plot, path)
}

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
    let fail = |e: &dyn std::fmt::Display| PlotError { path: path.display().to_string(), message: e.to_string() };
    register_font();
    let half_fov = camera.horizontal_fov() / 2.0;
    let x_max = max_depth * half_fov.tan();
    let root = BitMapBackend::new(path, (1000, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| fail(&e))?;
    let (map_area, bar_area) = root.split_horizontally(890);
    let mut chart = ChartBuilder::on(&map_area)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(-x_max..x_max, 0.0..max_depth)
        .map_err(|e| fail(&e))?;
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
pub fn draw_environment_map(map: &crate::environment_map::EnvironmentMap, path: &Path) -> Result<(), PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError { path: path.display().to_string(), message: e.to_string() };
    register_font();
    let mut factors: Vec<&str> = Vec::new();
    for c in &map.cells {
        if !factors.contains(&c.factor) {
            factors.push(c.factor);
        }
    }
    let columns = factors.iter().map(|f| map.cells.iter().filter(|c| c.factor == *f).count()).max().unwrap_or(1);
    let (label_w, cell_w, cell_h, top, bottom) = (190i32, 190i32, 84i32, 70i32, 70i32);
    let width = (label_w + cell_w * columns as i32 + 20) as u32;
    let height = (top + cell_h * factors.len() as i32 + bottom) as u32;
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
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
    let note = "Each cell: the level, the aided technique with the least error on the development seeds, and its error over straight driving's on held-out runs with 95 % CI. Green: aiding pays; red: it costs. Outlined: the base route.";
    let at = (12, top + cell_h * factors.len() as i32 + 20);
    root.draw(&Text::new(note, at, ("sans-serif", 13))).map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}
