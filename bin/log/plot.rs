//! `vrpn_log plot FILE DEVICE [-o OUT.png|OUT.svg]`: the pictures that judge a recording, in
//! one image: x, y and z against time and a top view (x–y) per sensor, analog channels,
//! button timelines, dial turns, and the intervals between reports with their histogram.
//! Drawn with plotters into a PNG (encoded with `png`) or an SVG; the text uses a font built
//! into the program, so no system fonts are needed.

#[path = "plot_data.rs"]
mod plot_data;

use std::error::Error;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, Palette, Palette99};

pub use plot_data::{read, PlotData};

/// DejaVu Sans, cut down to the characters used (see dejavu-sans-subset.LICENSE).
const FONT: &[u8] = include_bytes!("dejavu-sans-subset.ttf");
const FAMILY: &str = "sans-serif";

const WIDTH: u32 = 1200;
const TITLE_H: u32 = 44;
const TRAJECTORY_H: u32 = 420;
const ANALOG_H: u32 = 230;
const DIAL_H: u32 = 200;
const INTERVAL_H: u32 = 260;
/// Points drawn per line at most (longer series are thinned evenly; an SVG of a long
/// 1 kHz recording would otherwise be tens of megabytes).
const MAX_POINTS: usize = 4000;
/// Interval points drawn at most per stream; the ones far from the median are always kept.
const MAX_INTERVAL_POINTS: usize = 20_000;

type Res = Result<(), Box<dyn Error>>;

/// An axis number without float noise: `-0` as `0`, at most four decimals, no trailing
/// zeros.
fn num(v: &f64) -> String {
    let v = if v.abs() < 1e-9 { 0.0 } else { *v };
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// A count on an axis.
fn whole(v: &f64) -> String {
    format!("{v:.0}")
}

/// Output format, from the file name.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

impl Format {
    /// `.png` or `.svg` (any case); `None` for anything else.
    pub fn of(path: &str) -> Option<Format> {
        let ext = Path::new(path).extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Format::Png),
            "svg" => Some(Format::Svg),
            _ => None,
        }
    }
}

fn colour(i: usize) -> RGBColor {
    let (r, g, b) = Palette99::COLORS[i % Palette99::COLORS.len()];
    RGBColor(r, g, b)
}

fn height_buttons(n: usize) -> u32 {
    70 + 26 * n.min(32) as u32
}

/// The image's height for `d`'s panels.
fn height(d: &PlotData) -> u32 {
    let mut h = TITLE_H;
    if !d.poses.is_empty() {
        h += TRAJECTORY_H;
    }
    if !d.analog.is_empty() {
        h += ANALOG_H;
    }
    if !d.buttons.is_empty() {
        h += height_buttons(d.buttons.len());
    }
    if !d.dials.is_empty() {
        h += DIAL_H;
    }
    if !d.intervals.is_empty() {
        h += INTERVAL_H;
    }
    h
}

/// Draws `d` into `out` (PNG or SVG by `format`).
pub fn render(d: &PlotData, out: &str, format: Format) -> Res {
    // Registering twice (in tests) only replaces the same font.
    plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
        .map_err(|_| "the built-in font is not a valid font")?;
    let size = (WIDTH, height(d));
    match format {
        Format::Svg => {
            let root = SVGBackend::new(out, size).into_drawing_area();
            draw(&root, d)?;
            root.present()?;
        }
        Format::Png => {
            let mut rgb = vec![0u8; (size.0 * size.1 * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                draw(&root, d)?;
                root.present()?;
            }
            let file = std::io::BufWriter::new(std::fs::File::create(out)?);
            let mut png = png::Encoder::new(file, size.0, size.1);
            png.set_color(png::ColorType::Rgb);
            png.set_depth(png::BitDepth::Eight);
            // Flat colours and lines: the adaptive filter with the best compression makes
            // the file several times smaller than the defaults do.
            png.set_compression(png::Compression::Best);
            png.set_filter(png::FilterType::Paeth);
            png.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
            png.write_header()?.write_image_data(&rgb)?;
        }
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (title, mut rest) = root.split_vertically(TITLE_H);
    let reports: usize = d.intervals.values().map(|v| v.len() + 1).sum();
    title.draw(&Text::new(
        format!(
            "{}: {reports} reports over {:.3} s (time 0 = {:.6} s since 1970)",
            d.device, d.end, d.start
        ),
        (12, 12),
        (FAMILY, 20).into_font(),
    ))?;
    if !d.poses.is_empty() {
        let (a, b) = rest.split_vertically(TRAJECTORY_H);
        trajectories(&a, d)?;
        rest = b;
    }
    if !d.analog.is_empty() {
        let (a, b) = rest.split_vertically(ANALOG_H);
        analog(&a, d)?;
        rest = b;
    }
    if !d.buttons.is_empty() {
        let (a, b) = rest.split_vertically(height_buttons(d.buttons.len()));
        buttons(&a, d)?;
        rest = b;
    }
    if !d.dials.is_empty() {
        let (a, b) = rest.split_vertically(DIAL_H);
        dials(&a, d)?;
        rest = b;
    }
    if !d.intervals.is_empty() {
        intervals(&rest, d)?;
    }
    Ok(())
}

/// `lo..hi` widened a little, and made non-empty.
fn padded(lo: f64, hi: f64) -> std::ops::Range<f64> {
    if !(lo.is_finite() && hi.is_finite()) {
        return 0.0..1.0;
    }
    let span = (hi - lo).max(1e-3);
    let mid = (lo + hi) / 2.0;
    let half = span / 2.0 * 1.08;
    (mid - half)..(mid + half)
}

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// Every `k`-th element so that at most `max` remain (the last one always).
fn thin<T: Copy>(v: &[T], max: usize) -> Vec<T> {
    if v.len() <= max {
        return v.to_vec();
    }
    let k = v.len().div_ceil(max);
    let mut out: Vec<T> = v.iter().step_by(k).copied().collect();
    out.extend(v.last().copied());
    out
}

fn time_range(d: &PlotData) -> std::ops::Range<f64> {
    0.0..d.end.max(1e-3)
}

/// x, y, z against time (one chart each, a line per sensor) and the top view.
fn trajectories<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    let (left, right) = area.split_horizontally(WIDTH - 420);
    let rows = left.split_evenly((3, 1));
    for (axis, row) in rows.iter().enumerate() {
        let name = ["x", "y", "z"][axis];
        let (lo, hi) = bounds(d.poses.values().flatten().map(|p| p.1[axis]));
        let mut chart = ChartBuilder::on(row)
            .margin(6)
            .x_label_area_size(if axis == 2 { 30 } else { 18 })
            .y_label_area_size(70)
            .build_cartesian_2d(time_range(d), padded(lo, hi))?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(format!("{name} (m)"))
            .label_style((FAMILY, 12))
            .y_label_formatter(&num)
            .x_label_formatter(&num)
            .y_labels(5)
            .light_line_style(WHITE.mix(0.0));
        if axis == 2 {
            mesh.x_desc("time (s)");
        }
        mesh.draw()?;
        for (i, (sensor, poses)) in d.poses.iter().enumerate() {
            let line = thin(poses, MAX_POINTS)
                .into_iter()
                .map(|(t, p)| (t, p[axis]));
            let s = chart.draw_series(LineSeries::new(line, colour(i).stroke_width(2)))?;
            if axis == 0 {
                let c = colour(i);
                s.label(format!("sensor {sensor}"))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
            }
        }
        if axis == 0 && d.poses.len() > 1 {
            chart
                .configure_series_labels()
                .label_font((FAMILY, 12))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.3))
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }
    }
    // Top view, x across and y up, equal scales.
    let (xl, xh) = bounds(d.poses.values().flatten().map(|p| p.1[0]));
    let (yl, yh) = bounds(d.poses.values().flatten().map(|p| p.1[1]));
    let half = ((xh - xl).max(yh - yl).max(1e-3)) / 2.0 * 1.1;
    let (cx, cy) = ((xl + xh) / 2.0, (yl + yh) / 2.0);
    let mut top = ChartBuilder::on(&right)
        .margin(10)
        .caption("top view (x–y)", (FAMILY, 15))
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d((cx - half)..(cx + half), (cy - half)..(cy + half))?;
    top.configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_label_formatter(&num)
        .x_labels(5)
        .y_labels(5)
        .draw()?;
    for (i, poses) in d.poses.values().enumerate() {
        let line = thin(poses, MAX_POINTS)
            .into_iter()
            .map(|(_, p)| (p[0], p[1]));
        top.draw_series(LineSeries::new(line, colour(i).stroke_width(1)))?;
        if let (Some(first), Some(last)) = (poses.first(), poses.last()) {
            top.draw_series([
                Circle::new((first.1[0], first.1[1]), 4, colour(i).stroke_width(2)),
                Circle::new((last.1[0], last.1[1]), 4, colour(i).filled()),
            ])?;
        }
    }
    Ok(())
}

/// Analog channels against time.
fn analog<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    let n = d.analog.iter().map(|(_, c)| c.len()).max().unwrap_or(0);
    let (lo, hi) = bounds(d.analog.iter().flat_map(|(_, c)| c.iter().copied()));
    let mut chart = ChartBuilder::on(area)
        .margin(6)
        .caption("analog channels", (FAMILY, 15))
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(time_range(d), padded(lo, hi))?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("value")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_label_formatter(&num)
        .draw()?;
    let reports = thin(&d.analog.iter().enumerate().collect::<Vec<_>>(), MAX_POINTS);
    for ch in 0..n.min(32) {
        let line = reports
            .iter()
            .filter_map(|(_, (t, c))| c.get(ch).map(|v| (*t, *v)));
        let c = colour(ch);
        chart
            .draw_series(LineSeries::new(line, c.stroke_width(2)))?
            .label(format!("ch{ch}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 12))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

/// One band per button, filled while pressed.
fn buttons<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    let shown: Vec<(&i32, &Vec<(f64, bool)>)> = d.buttons.iter().take(32).collect();
    let n = shown.len() as f64;
    let labels: Vec<i32> = shown.iter().map(|(b, _)| **b).collect();
    let mut chart = ChartBuilder::on(area)
        .margin(6)
        .caption("buttons (filled while pressed)", (FAMILY, 15))
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(time_range(d), 0.0..n)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_labels(shown.len() * 2 + 1)
        .y_label_formatter(&|y| {
            let i = (y - 0.5).round();
            if (y - 0.5 - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
                format!("button {}", labels[i as usize])
            } else {
                String::new()
            }
        })
        .disable_y_mesh()
        .draw()?;
    for (row, (_, changes)) in shown.iter().enumerate() {
        let y = row as f64;
        let c = colour(row);
        let mut down: Option<f64> = None;
        let mut bars = Vec::new();
        for &(t, pressed) in changes.iter() {
            match (pressed, down) {
                (true, None) => down = Some(t),
                (false, Some(t0)) => {
                    bars.push((t0, t));
                    down = None;
                }
                _ => {}
            }
        }
        if let Some(t0) = down {
            bars.push((t0, d.end));
        }
        chart.draw_series(bars.into_iter().map(|(a, b)| {
            // A press shorter than a pixel still shows.
            let b = b.max(a + d.end.max(1e-3) / 2000.0);
            Rectangle::new([(a, y + 0.15), (b, y + 0.85)], c.filled())
        }))?;
        chart.draw_series(
            changes
                .iter()
                .filter(|c| c.1)
                .map(|&(t, _)| PathElement::new(vec![(t, y + 0.1), (t, y + 0.9)], BLACK)),
        )?;
    }
    Ok(())
}

/// Each dial's total turn against time.
fn dials<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    let (lo, hi) = bounds(d.dials.values().flatten().map(|p| p.1).chain([0.0]));
    let mut chart = ChartBuilder::on(area)
        .margin(6)
        .caption("dials (total turn)", (FAMILY, 15))
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(time_range(d), padded(lo, hi))?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("revolutions")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_label_formatter(&num)
        .draw()?;
    for (i, (dial, v)) in d.dials.iter().enumerate() {
        let c = colour(i);
        let steps = thin(v, MAX_POINTS);
        chart
            .draw_series(LineSeries::new(
                std::iter::once((0.0, 0.0)).chain(steps),
                c.stroke_width(2),
            ))?
            .label(format!("dial {dial}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 12))
        .background_style(WHITE.mix(0.8))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    Ok(())
}

/// Median of `v` (unsorted), 0 for an empty one.
fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// Interval points to draw: all when few, else an even thinning plus every outlier.
fn interval_points(v: &[(f64, f64)]) -> Vec<(f64, f64)> {
    if v.len() <= MAX_INTERVAL_POINTS {
        return v.to_vec();
    }
    let m = median(&v.iter().map(|p| p.1).collect::<Vec<_>>());
    let k = v.len().div_ceil(MAX_INTERVAL_POINTS);
    v.iter()
        .enumerate()
        .filter(|(i, p)| i % k == 0 || p.1 > 2.0 * m + 0.5 || p.1 < 0.5 * m)
        .map(|(_, p)| *p)
        .collect()
}

/// Report intervals against time, per stream, and their histogram.
fn intervals<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &PlotData) -> Res
where
    DB::ErrorType: 'static,
{
    let (left, right) = area.split_horizontally(WIDTH - 420);
    let all: Vec<f64> = d.intervals.values().flatten().map(|p| p.1).collect();
    let mut sorted = all.clone();
    sorted.sort_by(f64::total_cmp);
    let max = sorted.last().copied().unwrap_or(1.0).max(1e-3);
    let mut chart = ChartBuilder::on(&left)
        .margin(6)
        .caption("interval before each report", (FAMILY, 15))
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(time_range(d), 0.0..max * 1.05)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("interval (ms)")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_label_formatter(&num)
        .draw()?;
    for (i, (stream, v)) in d.intervals.iter().enumerate() {
        let c = colour(i);
        chart
            .draw_series(
                interval_points(v)
                    .into_iter()
                    .map(move |p| Circle::new(p, 1, c.filled())),
            )?
            .label(stream.clone())
            .legend(move |(x, y)| Circle::new((x + 8, y), 3, c.filled()));
    }
    if d.intervals.len() > 1 {
        chart
            .configure_series_labels()
            .label_font((FAMILY, 12))
            .background_style(WHITE.mix(0.8))
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
    }
    // Histogram up to the 99.5th percentile (a few long gaps would squash the rest; the
    // scatter shows them), 40 bins.
    let cap = sorted
        .get(((sorted.len() as f64) * 0.995) as usize)
        .copied()
        .unwrap_or(max)
        .max(1e-3)
        * 1.02;
    const BINS: usize = 40;
    let width = cap / BINS as f64;
    let mut counts = [0u64; BINS];
    let mut over = 0;
    for v in &all {
        let b = (v / width) as usize;
        match counts.get_mut(b) {
            Some(c) => *c += 1,
            None => over += 1,
        }
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64;
    let caption = format!(
        "intervals: median {:.3} ms{}",
        median(&all),
        if over > 0 {
            format!(", {over} beyond {cap:.2} ms")
        } else {
            String::new()
        }
    );
    let mut hist = ChartBuilder::on(&right)
        .margin(10)
        .caption(caption, (FAMILY, 14))
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..cap, 0.0..top * 1.08)?;
    hist.configure_mesh()
        .x_desc("interval (ms)")
        .y_desc("reports")
        .label_style((FAMILY, 12))
        .x_label_formatter(&num)
        .y_label_formatter(&whole)
        .x_labels(5)
        .draw()?;
    hist.draw_series(
        counts
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0)
            .map(|(i, c)| {
                let x0 = i as f64 * width;
                Rectangle::new(
                    [(x0, 0.0), (x0 + width * 0.9, *c as f64)],
                    colour(0).filled(),
                )
            }),
    )?;
    Ok(())
}
