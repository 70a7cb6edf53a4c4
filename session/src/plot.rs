//! `plot.png`: the world and the run seen from above, as in the thesis's
//! figure 31: walls, landmarks, the true and the estimated paths, and the
//! points where the robot changed its mind.

use crate::json_topics::WorldMessage;
use crate::replay::{Decision, ReplayedRun, Timeline};
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;
use std::sync::Once;
use ubf_core::Goal;

/// What a run plot shows.
pub struct RunPlot<'a> {
    /// The caption.
    pub title: &'a str,
    /// Walls (and boxes), landmarks, people at the start, featureless
    /// stretches: as the run log carries them, so a log alone redraws it.
    pub world: &'a WorldMessage,
    /// Where the robot really went.
    pub true_path: &'a [(f64, f64)],
    /// Where it believed it went.
    pub estimated_path: &'a [(f64, f64)],
    /// Where the winning behaviour changed, on the true path, and the
    /// behaviour that won there.
    pub decisions: &'a [Decision],
    /// Where the robot touched something, on the true path.
    pub collisions: &'a [(f64, f64)],
    /// The robot's pose at its start, and its outline there.
    pub start: Option<(ubf_core::Pose2, [(f64, f64); 4])>,
    /// The goal.
    pub goal: Option<Goal>,
    /// Speed, turn rate and votes over time, for the panel under the map.
    pub timeline: Option<&'a Timeline>,
}

/// Decision points labelled on the map at most; beyond, the crosses speak
/// for themselves (a scan decides hundreds of times).
const MOST_LABELS: usize = 40;

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("drawing {path}: {message}")]
pub struct PlotError {
    path: String,
    message: String,
}

impl PlotError {
    /// Drawing `path` failed, for the reason `message`.
    pub fn new(path: &Path, message: impl std::fmt::Display) -> PlotError {
        PlotError { path: path.display().to_string(), message: message.to_string() }
    }
}

/// A white canvas of `size` pixels that will be saved as a PNG at `path`.
/// The file is created first, so an unwritable path is said in words
/// rather than in the drawing library's debug text when it saves.
pub fn canvas(
    path: &Path,
    size: (u32, u32),
) -> Result<DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>, PlotError> {
    std::fs::File::create(path).map_err(|e| PlotError::new(path, format!("cannot create the file: {e}")))?;
    register_font();
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| PlotError::new(path, e))?;
    Ok(root)
}

/// The ranges to plot so that a metre is as many pixels across as up, in a
/// plotting area of `pixels`: the narrower of `bounds`' two ranges is
/// widened about its centre. Maps that stretch one axis make a square room
/// look like a corridor.
pub fn equal_scale(bounds: (f64, f64, f64, f64), pixels: (u32, u32)) -> (Range<f64>, Range<f64>) {
    let (x0, x1, y0, y1) = bounds;
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    let metres_per_pixel = ((x1 - x0) / w).max((y1 - y0) / h);
    let widen = |lo: f64, hi: f64, span: f64| {
        let centre = (lo + hi) / 2.0;
        (centre - span / 2.0)..(centre + span / 2.0)
    };
    (widen(x0, x1, metres_per_pixel * w), widen(y0, y1, metres_per_pixel * h))
}

/// `text` broken into lines at spaces so that none is wider than
/// `max_width` pixels in the plots' font at `size` points (a word longer
/// than that stands alone).
pub fn wrap_text(text: &str, size: f64, max_width: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), size) <= max_width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_owned()),
        }
    }
    lines
}

/// How wide `text` is in the plots' font at `size` points, pixels.
pub fn text_width(text: &str, size: f64) -> u32 {
    register_font();
    ("sans-serif", size).into_font().box_size(text).map_or(0, |(w, _)| w)
}

static FONT: Once = Once::new();

/// Registers the font plots are drawn with, once; call it before drawing
/// text. The font ships inside a crate, so plots need no system font
/// libraries.
fn register_font() {
    FONT.call_once(|| {
        // Registering a valid built-in font cannot fail; if it somehow did,
        // text would be missing, not the plot.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

fn bounds(plot: &RunPlot) -> (f64, f64, f64, f64) {
    let mut points: Vec<(f64, f64)> = plot.true_path.iter().chain(plot.estimated_path).copied().collect();
    for [a, b] in &plot.world.segments {
        points.extend([(a[0], a[1]), (b[0], b[1])]);
    }
    points.extend(plot.world.landmarks.iter().map(|p| (p[0], p[1])));
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

/// The turn rate's colour.
const TURN: RGBColor = RGBColor(200, 90, 0);

/// The camera pan's colour.
const CAMERA_PAN: RGBColor = RGBColor(120, 40, 160);

/// The legends' text size, points.
const LEGEND_TEXT: f64 = 16.0;

/// Where the legends' text starts, pixels from the left of their column.
const LEGEND_TEXT_AT: i32 = 44;

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
enum Mark {
    Dot(RGBColor, i32),
    Ring(RGBColor, i32),
    Line(RGBColor, u32),
    Cross(RGBColor),
    Triangle(RGBColor),
    Outline(RGBColor),
    Band(RGBColor),
}

/// The legend, in its own column beside the map so it never hides any of
/// the world.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[(String, Mark)],
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    for (i, (label, mark)) in entries.iter().enumerate() {
        let y = 60 + 28 * i as i32;
        let (x, c) = (22, (22, y));
        match *mark {
            Mark::Dot(color, r) => area.draw(&Circle::new(c, r, color.filled())),
            Mark::Ring(color, r) => area.draw(&Circle::new(c, r, color.stroke_width(2))),
            Mark::Line(color, w) => area.draw(&PathElement::new(vec![(x - 12, y), (x + 12, y)], color.stroke_width(w))),
            Mark::Cross(color) => area.draw(&Cross::new(c, 5, color.stroke_width(2))),
            Mark::Triangle(color) => area.draw(&TriangleMarker::new(c, 8, color.stroke_width(2))),
            Mark::Outline(color) => area.draw(&Rectangle::new([(x - 9, y - 6), (x + 9, y + 6)], color.stroke_width(2))),
            Mark::Band(color) => area.draw(&Rectangle::new([(x - 12, y - 3), (x + 12, y + 3)], color.filled())),
        }
        .map_err(|e| err(&e))?;
        area.draw(&Text::new(label.clone(), (LEGEND_TEXT_AT, y - 8), ("sans-serif", LEGEND_TEXT)))
            .map_err(|e| err(&e))?;
    }
    Ok(())
}

/// Draws the plot into a PNG at `path`: the world from above with the
/// legend beside it and, with a timeline, speed, turn rate and votes over
/// time underneath.
pub fn draw(plot: &RunPlot, path: &Path) -> Result<(), PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError { path: path.display().to_string(), message: e.to_string() };
    let (x0, x1, y0, y1) = bounds(plot);
    // Equal scales on both axes, so a corridor looks like one.
    let (width, legend_width) = (1400u32, 230u32);
    let plot_width = f64::from(width - legend_width - 90);
    let map_height = ((plot_width * (y1 - y0) / (x1 - x0)) as u32 + 110).clamp(300, 1400);
    let panel_height = if plot.timeline.is_some() { 420 } else { 0 };
    let root = canvas(path, (width, map_height + panel_height))?;
    let (top, panel) = root.split_vertically(map_height);
    let (map_area, legend_area) = top.split_horizontally(width - legend_width);
    let map_area = map_area.margin(8, 0, 0, 0).titled(plot.title, ("sans-serif", 22)).map_err(|e| fail(&e))?;
    let chart_on = |x: Range<f64>, y: Range<f64>| {
        ChartBuilder::on(&map_area).margin(12).x_label_area_size(36).y_label_area_size(50).build_cartesian_2d(x, y)
    };
    let pixels = chart_on(0.0..1.0, 0.0..1.0).map_err(|e| fail(&e))?.plotting_area().dim_in_pixel();
    let (x_range, y_range) = equal_scale((x0, x1, y0, y1), pixels);
    let mut chart = chart_on(x_range, y_range).map_err(|e| fail(&e))?;
    chart.configure_mesh().x_desc("x (m)").y_desc("y (m)").light_line_style(WHITE).draw().map_err(|e| fail(&e))?;
    let mut legend: Vec<(String, Mark)> = Vec::new();

    let wall = ShapeStyle::from(&BLACK).stroke_width(2);
    chart
        .draw_series(plot.world.segments.iter().map(|[a, b]| PathElement::new(vec![(a[0], a[1]), (b[0], b[1])], wall)))
        .map_err(|e| fail(&e))?;
    // Featureless stretches of the corridor's side walls, drawn along them.
    let bare = RGBColor(170, 170, 170);
    if !plot.world.featureless.is_empty() {
        chart
            .draw_series(
                plot.world
                    .featureless
                    .iter()
                    .map(|[a, b]| PathElement::new(vec![(a[0], a[1]), (b[0], b[1])], bare.stroke_width(7))),
            )
            .map_err(|e| fail(&e))?;
        legend.push(("featureless wall".into(), Mark::Band(bare)));
    }
    // Only what the plot shows goes in the legend.
    let landmark = RED;
    let fixed: Vec<(f64, f64)> = plot.world.landmarks.iter().map(|p| (p[0], p[1])).collect();
    if !fixed.is_empty() {
        chart.draw_series(fixed.iter().map(|&p| Circle::new(p, 4, landmark.filled()))).map_err(|e| fail(&e))?;
        legend.push(("landmark".into(), Mark::Dot(landmark, 4)));
    }
    let person = RGBColor(230, 140, 0);
    if !plot.world.people.is_empty() {
        chart
            .draw_series(plot.world.people.iter().map(|p| Circle::new((p[0], p[1]), 6, person.stroke_width(2))))
            .map_err(|e| fail(&e))?;
        legend.push(("person (at the start)".into(), Mark::Ring(person, 6)));
    }
    let truth = RGBColor(30, 80, 200);
    let estimate = RGBColor(20, 150, 60);
    if let Some((pose, outline)) = plot.start {
        let mut closed = outline.to_vec();
        closed.push(outline[0]);
        chart.draw_series([PathElement::new(closed, BLACK.stroke_width(2))]).map_err(|e| fail(&e))?;
        // The heading: from the centre of rotation to the outline's front.
        let reach = outline
            .iter()
            .map(|p| (p.0 - pose.x) * pose.theta.cos() + (p.1 - pose.y) * pose.theta.sin())
            .fold(0.0, f64::max);
        let front = (pose.x + reach * pose.theta.cos(), pose.y + reach * pose.theta.sin());
        chart
            .draw_series([PathElement::new(vec![(pose.x, pose.y), front], BLACK.stroke_width(3))])
            .map_err(|e| fail(&e))?;
        legend.push(("robot at the start".into(), Mark::Outline(BLACK)));
    }
    if !plot.true_path.is_empty() {
        chart
            .draw_series(LineSeries::new(plot.true_path.iter().copied(), truth.stroke_width(2)))
            .map_err(|e| fail(&e))?;
        legend.push(("true path".into(), Mark::Line(truth, 2)));
    }
    if !plot.estimated_path.is_empty() {
        chart
            .draw_series(LineSeries::new(plot.estimated_path.iter().copied(), estimate.stroke_width(1)))
            .map_err(|e| fail(&e))?;
        legend.push(("estimated path".into(), Mark::Line(estimate, 1)));
    }
    if !plot.decisions.is_empty() {
        chart
            .draw_series(plot.decisions.iter().map(|d| Cross::new(d.at, 5, truth.stroke_width(2))))
            .map_err(|e| fail(&e))?;
        if plot.decisions.len() <= MOST_LABELS {
            // A label each, but not on top of the last one drawn.
            let apart = 0.04 * (x1 - x0).max(y1 - y0);
            let mut labelled: Vec<&Decision> = Vec::new();
            for d in plot.decisions {
                if labelled.last().is_none_or(|l| (l.at.0 - d.at.0).hypot(l.at.1 - d.at.1) > apart) {
                    labelled.push(d);
                }
            }
            chart
                .draw_series(
                    labelled
                        .iter()
                        .map(|d| Text::new(d.winner.clone(), d.at, ("sans-serif", 13).into_font().color(&truth))),
                )
                .map_err(|e| fail(&e))?;
            legend.push(("decision: the new winner".into(), Mark::Cross(truth)));
        } else {
            legend.push((format!("decision ({})", plot.decisions.len()), Mark::Cross(truth)));
        }
    }
    let contact = RGBColor(200, 0, 0);
    if !plot.collisions.is_empty() {
        chart
            .draw_series(plot.collisions.iter().map(|&p| Cross::new(p, 9, contact.stroke_width(3))))
            .map_err(|e| fail(&e))?;
        legend.push((format!("collision ({})", plot.collisions.len()), Mark::Cross(contact)));
    }
    if let Some(g) = plot.goal {
        chart.draw_series([TriangleMarker::new((g.x, g.y), 8, BLACK.stroke_width(2))]).map_err(|e| fail(&e))?;
        legend.push(("goal".into(), Mark::Triangle(BLACK)));
    }
    draw_legend(&legend_area, &legend).map_err(|e| fail(&e))?;
    if let Some(timeline) = plot.timeline {
        let (panel, legends) = panel.split_horizontally(width - legend_width);
        draw_timeline(&panel, timeline).map_err(|e| fail(&e))?;
        // The legends beside the panels, as the map's, so that they hide no
        // line: the camera's beside the turn panel (the second of three),
        // the votes' beside the vote panel (the third).
        if !timeline.camera_pan_deg.is_empty() {
            let (_, beside_turn) = legends.split_vertically(panel_height / 3 - 40);
            let entries = [("turn rate".into(), Mark::Line(TURN, 1)), ("camera pan".into(), Mark::Line(CAMERA_PAN, 2))];
            draw_legend(&beside_turn, &entries).map_err(|e| fail(&e))?;
        }
        let (_, beside_votes) = legends.split_vertically(panel_height * 2 / 3 - 40);
        let entries = vote_legend(timeline, legend_width - LEGEND_TEXT_AT as u32 - 8);
        draw_legend(&beside_votes, &entries).map_err(|e| fail(&e))?;
    }
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

/// Speed, turn rate and every behaviour's vote against time, one above the
/// other, sharing the time axis.
fn draw_timeline<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    timeline: &Timeline,
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let end = timeline.time.last().copied().unwrap_or(1.0).max(1e-3);
    let rows = area.split_evenly((3, 1));
    let finite_range = |values: &[f64]| {
        let (lo, hi) =
            values.iter().filter(|v| v.is_finite()).fold((0.0f64, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
        let pad = 0.1 * (hi - lo).max(0.1);
        (lo - pad)..(hi + pad)
    };
    let series: [(&str, &[f64], RGBColor); 2] =
        [("speed (m/s)", &timeline.speed, RGBColor(30, 80, 200)), ("turn rate (°/s)", &timeline.turn_deg, TURN)];
    for (row, (label, values, color)) in rows.iter().zip(series) {
        // The camera's pan shares the turn panel, on the same axis, in °.
        let pan = (label.starts_with("turn") && !timeline.camera_pan_deg.is_empty())
            .then_some(timeline.camera_pan_deg.as_slice());
        let range = finite_range(&[values, pan.unwrap_or_default()].concat());
        let label = if pan.is_some() { "turn (°/s), pan (°)" } else { label };
        let mut chart = ChartBuilder::on(row)
            .margin(8)
            .x_label_area_size(24)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..end, range)
            .map_err(|e| err(&e))?;
        chart.configure_mesh().y_desc(label).light_line_style(WHITE).draw().map_err(|e| err(&e))?;
        let points = timeline.time.iter().zip(values).filter(|(_, v)| v.is_finite()).map(|(t, v)| (*t, *v));
        chart.draw_series(LineSeries::new(points, color.stroke_width(1))).map_err(|e| err(&e))?;
        if let Some(pan) = pan {
            let points = timeline.time.iter().zip(pan).filter(|(_, v)| v.is_finite()).map(|(t, v)| (*t, *v));
            chart.draw_series(LineSeries::new(points, CAMERA_PAN.stroke_width(2))).map_err(|e| err(&e))?;
        }
    }
    let top =
        timeline.votes.iter().flat_map(|(_, v)| v.iter()).copied().filter(|v| v.is_finite()).fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(&rows[2])
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..end, 0.0..top * 1.05)
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc("time (s)").y_desc("vote").light_line_style(WHITE).draw().map_err(|e| err(&e))?;
    for (i, (_, votes)) in timeline.votes.iter().enumerate() {
        let points = timeline.time.iter().zip(votes).filter(|(_, v)| v.is_finite()).map(|(t, v)| (*t, *v));
        chart.draw_series(LineSeries::new(points, vote_colour(i).stroke_width(1))).map_err(|e| err(&e))?;
    }
    Ok(())
}

/// The colour of the `i`th behaviour's votes.
fn vote_colour(i: usize) -> RGBColor {
    let RGBAColor(r, g, b, _) = Palette99::pick(i).to_rgba();
    RGBColor(r, g, b)
}

/// The votes' legend: each behaviour by its path in the tree, shortened
/// from the root end (`…/avoid/GoTo`) to what fits in `width` pixels.
fn vote_legend(timeline: &Timeline, width: u32) -> Vec<(String, Mark)> {
    let fit = |path: &str| {
        let mut shown = path.strip_prefix("root/").unwrap_or(path).to_owned();
        while text_width(&shown, LEGEND_TEXT) > width {
            match shown.trim_start_matches("…/").split_once('/') {
                Some((_, rest)) => shown = format!("…/{rest}"),
                None => break,
            }
        }
        shown
    };
    timeline.votes.iter().enumerate().map(|(i, (name, _))| (fit(name), Mark::Line(vote_colour(i), 2))).collect()
}

/// Draws a run as its log tells it (`ubf run` and `ubf replay` both draw
/// this way, so the two pictures cannot differ).
pub fn draw_replayed(run: &ReplayedRun, title: &str, path: &Path) -> Result<(), PlotError> {
    let start = run
        .run
        .as_ref()
        .map(|r| (ubf_core::Pose2::new(r.start[0], r.start[1], r.start[2]), r.outline.map(|[x, y]| (x, y))));
    let goal = run.run.as_ref().and_then(|r| r.goal).map(|[x, y, tolerance]| Goal { x, y, tolerance });
    let picture = RunPlot {
        title,
        world: &run.world,
        true_path: &run.true_path,
        estimated_path: &run.odometry_path,
        decisions: &run.decisions,
        collisions: &run.collisions,
        start,
        goal,
        timeline: Some(&run.timeline),
    };
    draw(&picture, path)
}

/// Draws a replayed sequence's egomotion path over the true one (when
/// there is one), from above: x ahead of the first pose, y to its left.
pub fn draw_paths(
    estimate: &[ubf_core::Pose2],
    truth: Option<&[ubf_core::Pose2]>,
    path: &Path,
) -> Result<(), PlotError> {
    let world = WorldMessage::default();
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
        collisions: &[],
        start: None,
        goal: None,
        timeline: None,
    };
    draw(&plot, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pixels of `png` darker than mid-grey, as a bounding box
    /// `(left, top, right, bottom)` within `region`.
    fn dark_box(png: &Path, region: (u32, u32, u32, u32)) -> (u32, u32, u32, u32) {
        let image = image::open(png).unwrap().to_luma8();
        let (mut left, mut top, mut right, mut bottom) = (u32::MAX, u32::MAX, 0, 0);
        for y in region.1..region.3 {
            for x in region.0..region.2 {
                if image.get_pixel(x, y).0[0] < 100 {
                    (left, top, right, bottom) = (left.min(x), top.min(y), right.max(x), bottom.max(y));
                }
            }
        }
        (left, top, right, bottom)
    }

    fn room(width: f64, depth: f64) -> WorldMessage {
        let corners = [[0.0, 0.0], [width, 0.0], [width, depth], [0.0, depth]];
        let segments = (0..4).map(|i| [corners[i], corners[(i + 1) % 4]]).collect();
        WorldMessage { segments, ..WorldMessage::default() }
    }

    #[test]
    fn a_square_room_is_drawn_square_and_a_corridor_long() {
        let dir = tempfile::tempdir().unwrap();
        for (width, depth) in [(10.0, 10.0), (60.0, 4.0), (3.0, 30.0)] {
            let world = room(width, depth);
            let path = dir.path().join("plot.png");
            let plot = RunPlot {
                title: "room",
                world: &world,
                true_path: &[],
                estimated_path: &[],
                decisions: &[],
                collisions: &[],
                start: None,
                goal: None,
                timeline: None,
            };
            draw(&plot, &path).unwrap();
            let (w, h) = image::image_dimensions(&path).unwrap();
            assert_eq!(w, 1400);
            // The walls: what is dark inside the axes, left of the legend.
            let image = image::open(&path).unwrap().to_luma8();
            let dark = |x: u32, y: u32| image.get_pixel(x, y).0[0] < 100;
            let y_axis = (0..w / 2).find(|&x| (0..h).filter(|&y| dark(x, y)).count() > h as usize / 2).unwrap();
            let x_axis = (0..h).rev().find(|&y| (0..w).filter(|&x| dark(x, y)).count() > w as usize / 2).unwrap();
            let (left, top, right, bottom) = dark_box(&path, (y_axis + 3, 40, w - 240, x_axis - 3));
            // The same pixels per metre both ways (less the walls' 2 px
            // stroke), to within rounding.
            let (across, up) = (f64::from(right - left) - 2.0, f64::from(bottom - top) - 2.0);
            let drawn = (up / depth) / (across / width);
            assert!((drawn - 1.0).abs() < 0.015, "{width}×{depth} m drawn {across} × {up} px");
        }
    }

    #[test]
    fn equal_scale_widens_the_narrower_range_about_its_centre() {
        let (x, y) = equal_scale((0.0, 10.0, -1.0, 1.0), (1000, 500));
        assert_eq!((x.start, x.end), (0.0, 10.0));
        assert_eq!((y.start, y.end), (-2.5, 2.5));
        let (x, y) = equal_scale((0.0, 1.0, 0.0, 10.0), (500, 500));
        assert_eq!((x.start, x.end, y.start, y.end), (-4.5, 5.5, 0.0, 10.0));
    }

    #[test]
    fn wrapped_text_fits_its_width() {
        let text = "Each cell: the level, the aided technique with the least error on the development seeds, and its \
                    error over straight driving's on held-out runs with 95 % CI.";
        let lines = wrap_text(text, 13.0, 300);
        assert!(lines.len() > 2, "{lines:?}");
        assert!(lines.iter().all(|l| text_width(l, 13.0) <= 300), "{lines:?}");
        assert_eq!(lines.join(" "), text.split_whitespace().collect::<Vec<_>>().join(" "));
    }
}
