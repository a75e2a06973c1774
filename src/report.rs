//! `leap report`: a trajectory file plotted against time, panel by panel,
//! after Moco's report (`opensim-moco report`, `Bindings/Python/report.py`):
//! sections of coordinate values, speeds and accelerations, activations,
//! normalized tendon forces, fibre lengths (leap's muscle state) and
//! excitations, then any other column (a `.mot`'s ground forces, Moco's
//! multipliers), three panels a row; reference files drawn first and
//! thicker beneath the trajectory, over the trajectory's time span; the y
//! axis held to [0, 1] for activations, excitations and normalized tendon
//! forces that lie in it; with `bilateral` a right
//! and a left column (`_r`, `_l`, also inside a name: `ground_force_l_vx`)
//! in one panel, the left dashed. Unlike Moco, each coordinate's values and
//! speeds are sections of their own, and Moco's parameter columns (one
//! value, then NaN) are left out. Written as one SVG page, which any
//! browser opens.
//!
//! Every file is read in radians: a file with `inDegrees=yes` has its
//! rotational coordinates' columns converted ([`crate::io::to_radians`]),
//! so that a file in degrees and one in radians overlay.

use crate::io::{ModelColumns, StoError, StoTable};
use plotters::prelude::*;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// A report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error(transparent)]
    Sto(#[from] StoError),
    #[error("{file}: {reason}")]
    Input { file: PathBuf, reason: String },
    #[error("drawing the report: {0}")]
    Draw(String),
}

/// The sections of a report, in Moco's order; `Other` holds what no other
/// section takes (ground forces of a `.mot`, say).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Section {
    CoordinateValues,
    CoordinateSpeeds,
    CoordinateAccelerations,
    Activations,
    NormalizedTendonForces,
    FiberLengths,
    Excitations,
    Other,
}

impl Section {
    pub fn title(self) -> &'static str {
        match self {
            Section::CoordinateValues => "coordinate values",
            Section::CoordinateSpeeds => "coordinate speeds",
            Section::CoordinateAccelerations => "coordinate accelerations",
            Section::Activations => "activations",
            Section::NormalizedTendonForces => "normalized tendon forces",
            Section::FiberLengths => "fibre lengths",
            Section::Excitations => "excitations",
            Section::Other => "other columns",
        }
    }
}

/// One file's column in a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Which file: 0 the trajectory, k the k-th reference.
    pub file: usize,
    /// The left column of a bilateral panel (drawn dashed).
    pub left: bool,
    pub time: Vec<f64>,
    pub values: Vec<f64>,
}

/// One panel: a quantity over time, from one or more files.
#[derive(Debug, Clone)]
pub struct Panel {
    pub section: Section,
    /// The coordinate's or muscle's name, or the column's label.
    pub title: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// A file to plot: its name in the legend and its table, in radians.
pub struct ReportFile {
    pub name: String,
    pub table: StoTable,
}

impl ReportFile {
    /// Read `path`: columns under OpenSim's pre-4.0 state names (an IK
    /// file's `hip_flexion_r`) renamed to the model's absolute paths, and
    /// the rotational coordinates' (`columns`, [`ModelColumns`]) converted
    /// from degrees where the header says `inDegrees=yes`. Time must increase
    /// over two rows or more, and every value be finite.
    pub fn read(path: &Path, columns: &ModelColumns) -> Result<Self, ReportError> {
        let mut table = StoTable::read(path)?;
        table.check_time(path, 2)?;
        table.check_finite(path)?;
        let degrees = table.in_degrees(path)?;
        crate::io::use_absolute_state_names(&mut table, &columns.pre_4_names);
        // A file in radians headed in degrees (or the reverse) would be
        // drawn 57 times too small (or large), without a word.
        crate::io::check_angle_units(&table, path, &columns.angle_ranges, degrees)?;
        crate::io::to_radians(&mut table, &columns.angular, degrees);
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        Ok(ReportFile { name, table })
    }
}

/// The section of a column, and the name its panel shows.
fn classify(label: &str) -> (Section, String) {
    let segments: Vec<&str> = label.split('/').filter(|s| !s.is_empty()).collect();
    let before_last = |n: usize| segments.get(segments.len().wrapping_sub(n)).copied();
    let last = before_last(1).unwrap_or(label);
    let owner = before_last(2).unwrap_or(label).to_string();
    if label.starts_with("/jointset/") && segments.len() == 4 {
        match last {
            "value" => return (Section::CoordinateValues, owner),
            "speed" => return (Section::CoordinateSpeeds, owner),
            "accel" => return (Section::CoordinateAccelerations, owner),
            _ => {}
        }
    }
    if label.starts_with("/forceset/") {
        match (segments.len(), last) {
            (2, name) => return (Section::Excitations, name.to_string()),
            (3, "activation") => return (Section::Activations, owner),
            (3, "normalized_tendon_force") => return (Section::NormalizedTendonForces, owner),
            (3, "fiber_length") => return (Section::FiberLengths, owner),
            _ => {}
        }
    }
    (Section::Other, label.to_string())
}

/// The y axis label of a panel.
fn y_label(section: Section, label: &str, angular: &HashSet<String>) -> String {
    let angle = angular.contains(label)
        || label
            .strip_suffix("/accel")
            .is_some_and(|c| angular.contains(&format!("{c}/value")));
    match section {
        Section::CoordinateValues if angle => "angle (rad)".into(),
        Section::CoordinateValues => "position (m)".into(),
        Section::CoordinateSpeeds if angle => "speed (rad/s)".into(),
        Section::CoordinateSpeeds => "speed (m/s)".into(),
        Section::CoordinateAccelerations if angle => "acceleration (rad/s²)".into(),
        Section::CoordinateAccelerations => "acceleration (m/s²)".into(),
        Section::NormalizedTendonForces => "tendon force / F0".into(),
        Section::Activations => "activation".into(),
        Section::FiberLengths => "fibre length (m)".into(),
        Section::Excitations => "excitation".into(),
        // OpenSim's ExternalLoads names: ground_force_vx (or
        // ground_force_r_vx, leap's), ground_force_px, ground_torque_x.
        Section::Other => {
            let ends = |ends: [&str; 3]| ends.iter().any(|e| label.ends_with(e));
            if label.contains("force") && ends(["_vx", "_vy", "_vz"]) {
                "force (N)".into()
            } else if label.contains("force") && ends(["_px", "_py", "_pz"]) {
                "point (m)".into()
            } else if label.contains("torque") && ends(["_x", "_y", "_z"]) {
                "torque (N·m)".into()
            } else {
                String::new()
            }
        }
    }
}

/// The right side's name of a left one: in each path segment a final
/// `_l` becomes `_r` (`/jointset/hip_l/hip_flexion_l/value`), and so does
/// an `_l_` inside it (`ground_force_l_vx`); None for a label with neither.
fn right_partner(label: &str) -> Option<String> {
    let mut changed = false;
    let segments: Vec<String> = label
        .split('/')
        .map(|s| {
            let mut side = s.replace("_l_", "_r_");
            if let Some(stem) = side.strip_suffix("_l") {
                side = format!("{stem}_r");
            }
            changed |= side != s;
            side
        })
        .collect();
    changed.then(|| segments.join("/"))
}

/// A right side's name without its side: `_r_` becomes `_`, a final `_r`
/// goes (`hip_flexion_r` → `hip_flexion`, `ground_force_r_vx` →
/// `ground_force_vx`).
fn side_free(name: &str) -> String {
    let name = name.replace("_r_", "_");
    name.strip_suffix("_r").map_or(name.clone(), str::to_string)
}

/// The panels of `files` (the trajectory first, then the references): one
/// per column of the trajectory, in the trajectory's column order within
/// the sections, each with the same column of every file that has it, the
/// references' cut to the trajectory's time span. With `bilateral`, a left
/// column whose right partner the trajectory has joins that panel, which
/// is then named without the side, and every left column is drawn dashed.
/// Columns only the references have are not plotted, nor a column with
/// fewer than two finite values (a Moco parameter's: its value, then
/// NaN); non-finite values are left out.
pub fn panels(files: &[ReportFile], bilateral: bool, angular: &HashSet<String>) -> Vec<Panel> {
    let Some(main) = files.first() else {
        return Vec::new();
    };
    let (t0, t1) = match (main.table.time.first(), main.table.time.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Vec::new(),
    };
    // Each file's column index by label (a file may have thousands).
    let columns: Vec<HashMap<&str, usize>> = files
        .iter()
        .map(|f| {
            f.table
                .labels
                .iter()
                .enumerate()
                .map(|(k, l)| (l.as_str(), k))
                .collect()
        })
        .collect();
    let mut panels: Vec<Panel> = Vec::new();
    let mut panel_of: HashMap<String, usize> = HashMap::new();
    for (k, label) in main.table.labels.iter().enumerate() {
        if main.table.rows.iter().filter(|r| r[k].is_finite()).count() < 2 {
            continue;
        }
        let right = if bilateral {
            right_partner(label)
        } else {
            None
        };
        let left = right.is_some();
        let partner = right.filter(|r| columns[0].contains_key(r.as_str()));
        let key = partner.clone().unwrap_or_else(|| label.clone());
        let index = *panel_of.entry(key.clone()).or_insert_with(|| {
            let (section, title) = classify(&key);
            panels.push(Panel {
                section,
                title,
                y_label: y_label(section, &key, angular),
                series: Vec::new(),
            });
            panels.len() - 1
        });
        // A panel holding both sides is named without the side, as
        // Moco's bilateral report names it.
        if partner.is_some() {
            panels[index].title = side_free(&panels[index].title);
        }
        for (file, (f, cols)) in files.iter().zip(&columns).enumerate() {
            let Some(&c) = cols.get(label.as_str()) else {
                continue;
            };
            let (time, values) = f
                .table
                .time
                .iter()
                .zip(&f.table.rows)
                .filter(|(t, _)| (t0..=t1).contains(*t))
                .map(|(t, r)| (*t, r[c]))
                .unzip();
            panels[index].series.push(Series {
                file,
                left,
                time,
                values,
            });
        }
    }
    // References beneath the trajectory; a stable sort keeps the columns'
    // order within each section.
    for p in &mut panels {
        p.series.sort_by_key(|s| std::cmp::Reverse(s.file));
    }
    panels.sort_by_key(|p| p.section);
    panels
}

/// Panel size and layout of the page (pixels).
const PANEL_WIDTH: u32 = 330;
const PANEL_HEIGHT: u32 = 230;
const COLUMNS: u32 = 3;
const SECTION_HEADING: u32 = 34;
const LEGEND_HEIGHT: u32 = 30;

/// The files' colours: the trajectory's first (Moco samples a colormap).
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// A closed range of time or values: (from, to).
pub type Range = (f64, f64);

/// The range of finite values in `values`, or None.
fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.filter(|v| v.is_finite()).fold(None, |r, v| match r {
        None => Some((v, v)),
        Some((a, b)) => Some((v.min(a), v.max(b))),
    })
}

/// The time and y ranges of a panel. Time: the span of its series. y:
/// [0, 1] for activations, excitations and normalized tendon forces whose
/// finite values all lie in it (Moco's rule; a fibre length in metres or a
/// centre of pressure near 0.1 m on it had drawn a flat line), else the
/// values' range widened by 5% of its size (a constant by 5% of its
/// magnitude, at least 0.5). An error where a range is empty or its span
/// overflows a double (plotters would not finish).
pub fn panel_ranges(p: &Panel) -> Result<(Range, Range), String> {
    let (t0, t1) = finite_range(p.series.iter().flat_map(|s| s.time.iter().copied()))
        .ok_or("no time to plot")?;
    let (lo, hi) = finite_range(p.series.iter().flat_map(|s| s.values.iter().copied()))
        .ok_or("no finite value to plot")?;
    let unit_interval = matches!(
        p.section,
        Section::Activations | Section::Excitations | Section::NormalizedTendonForces
    );
    // A span below a billionth of the values' magnitude (or 1e-12) is
    // rounding: drawn as a constant (plotters gives a span below 2.2e-16
    // one tick, and labels cannot tell ticks 1e-14 apart at 0.7).
    let constant = hi - lo <= (1e-9 * lo.abs().max(hi.abs())).max(1e-12);
    let y = if unit_interval && lo >= 0.0 && hi <= 1.0 {
        (0.0, 1.0)
    } else {
        let pad = if !constant {
            0.05 * (hi - lo)
        } else {
            0.05 * lo.abs().max(10.0)
        };
        (lo - pad, hi + pad)
    };
    let t = if t1 > t0 {
        (t0, t1)
    } else {
        (t0 - 0.5, t0 + 0.5)
    };
    for ((a, b), what) in [(t, "times"), (y, "values")] {
        if !(a.is_finite() && b.is_finite() && (b - a).is_finite()) {
            return Err(format!(
                "{what} from {} to {}: the span overflows a double, nothing to draw",
                crate::io::readable(a),
                crate::io::readable(b)
            ));
        }
    }
    Ok((t, y))
}

/// The points of one series to draw: all of them when there are few, else
/// per time bucket (`buckets` over [t0, t1]) the first, lowest, highest
/// and last, in time order, which draws the same line at the page's
/// resolution. Non-finite values are left out.
fn thinned(s: &Series, (t0, t1): (f64, f64), buckets: usize) -> Vec<(f64, f64)> {
    let points = s
        .time
        .iter()
        .copied()
        .zip(s.values.iter().copied())
        .filter(|(_, v)| v.is_finite());
    if s.time.len() <= 4 * buckets || t1 <= t0 {
        return points.collect();
    }
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut bucket: Vec<(f64, f64)> = Vec::new();
    let mut current = None;
    let flush = |bucket: &mut Vec<(f64, f64)>, out: &mut Vec<(f64, f64)>| {
        if bucket.is_empty() {
            return;
        }
        let by_value = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        let (first, last) = (bucket[0], bucket[bucket.len() - 1]);
        let lo = *bucket.iter().min_by(by_value).unwrap_or(&first);
        let hi = *bucket.iter().max_by(by_value).unwrap_or(&first);
        let mut keep = vec![first, lo, hi, last];
        keep.sort_by(|a, b| a.0.total_cmp(&b.0));
        keep.dedup();
        out.extend(keep);
        bucket.clear();
    };
    for (t, v) in points {
        let k = (((t - t0) / (t1 - t0)) * buckets as f64).floor() as i64;
        if current != Some(k) {
            flush(&mut bucket, &mut out);
            current = Some(k);
        }
        bucket.push((t, v));
    }
    flush(&mut bucket, &mut out);
    out
}

/// The panels of each section, in the panels' order.
pub fn sections(panels: &[Panel]) -> Vec<(Section, Vec<&Panel>)> {
    let mut sections: Vec<(Section, Vec<&Panel>)> = Vec::new();
    for p in panels {
        match sections.last_mut() {
            Some((s, ps)) if *s == p.section => ps.push(p),
            _ => sections.push((p.section, vec![p])),
        }
    }
    sections
}

/// The report of `panels` as one SVG page, with `title` on top and a
/// legend naming `files` (their line styles).
pub fn svg(
    title: &str,
    files: &[String],
    panels: &[Panel],
    bilateral: bool,
) -> Result<String, ReportError> {
    let draw = |e: &dyn std::fmt::Display| ReportError::Draw(e.to_string());
    let sections = sections(panels);
    let mut ranges = Vec::with_capacity(panels.len());
    for p in panels {
        ranges.push(panel_ranges(p).map_err(|r| {
            ReportError::Draw(format!("panel '{}' ({}): {r}", p.title, p.section.title()))
        })?);
    }
    let width = COLUMNS * PANEL_WIDTH;
    // The legend: one entry per file (a sample line and its name), on as
    // many lines as the page's width needs.
    let entries: Vec<String> = files
        .iter()
        .enumerate()
        .map(|(k, name)| {
            if k == 0 {
                name.clone()
            } else {
                format!("{name} (reference)")
            }
        })
        .chain(bilateral.then(|| "right solid, left dashed".to_string()))
        .collect();
    let mut places = Vec::with_capacity(entries.len());
    let (mut x, mut line) = (10i32, 0i32);
    for e in &entries {
        let w = 50 + 7 * e.chars().count() as i32;
        if x > 10 && x + w > width as i32 {
            (x, line) = (10, line + 1);
        }
        places.push((x, line));
        x += w;
    }
    let legend_height = LEGEND_HEIGHT * (line as u32 + 1);
    let rows = |n: usize| (n as u32).div_ceil(COLUMNS);
    let height = legend_height
        + 40
        + sections
            .iter()
            .map(|(_, ps)| SECTION_HEADING + rows(ps.len()) * PANEL_HEIGHT)
            .sum::<u32>();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw(&e))?;
        root.draw(&Text::new(title.to_string(), (10, 8), ("sans-serif", 18)))
            .map_err(|e| draw(&e))?;
        for (k, (e, &(x, line))) in entries.iter().zip(&places).enumerate() {
            let y = 40 + LEGEND_HEIGHT as i32 * line + LEGEND_HEIGHT as i32 / 2;
            if k < files.len() {
                root.draw(&PathElement::new(vec![(x, y), (x + 30, y)], line_style(k)))
                    .map_err(|e| draw(&e))?;
            }
            root.draw(&Text::new(e.clone(), (x + 36, y - 7), ("sans-serif", 13)))
                .map_err(|e| draw(&e))?;
        }
        let mut top = 40 + legend_height as i32;
        let mut ranges = ranges.iter();
        for (section, ps) in &sections {
            root.draw(&Text::new(
                section.title().to_string(),
                (10, top + 10),
                ("sans-serif", 16),
            ))
            .map_err(|e| draw(&e))?;
            top += SECTION_HEADING as i32;
            for (i, p) in ps.iter().enumerate() {
                let (c, r) = (i as u32 % COLUMNS, i as u32 / COLUMNS);
                let x0 = (c * PANEL_WIDTH) as i32;
                let y0 = top + (r * PANEL_HEIGHT) as i32;
                let area = root.clone().shrink((x0, y0), (PANEL_WIDTH, PANEL_HEIGHT));
                let Some(&(t, y)) = ranges.next() else {
                    return Err(ReportError::Draw("a panel without its ranges".into()));
                };
                draw_panel(&area, p, t, y).map_err(|e| draw(&e))?;
            }
            top += (rows(ps.len()) * PANEL_HEIGHT) as i32;
        }
        root.present().map_err(|e| draw(&e))?;
    }
    Ok(out)
}

/// The line of file `k`: references thicker and lighter, beneath the
/// trajectory, as Moco draws them.
fn line_style(k: usize) -> ShapeStyle {
    // References cycle through the colours after the trajectory's.
    let colour = match k {
        0 => COLOURS[0],
        k => COLOURS[1 + (k - 1) % (COLOURS.len() - 1)],
    };
    if k == 0 {
        colour.stroke_width(2)
    } else {
        colour.mix(0.6).stroke_width(4)
    }
}

/// How an axis over `(lo, hi)` writes its ticks: the spacing plotters
/// places them at ({1, 2, 5}·10^m; NaN where it places fewer than two)
/// and the axis's largest magnitude ([`tick_label`]).
fn tick_spacing((lo, hi): Range) -> (f64, f64) {
    let ticks = plotters::coord::types::RangedCoordf64::from(lo..hi).key_points(TICKS);
    let step = ticks
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    (step, lo.abs().max(hi.abs()))
}

/// The text of the tick at `v` on an axis of `(step, magnitude)`
/// ([`tick_spacing`]): with the decimals of the ticks' spacing (every tick
/// apart and alike; plotters' own text repeated "-0.4352" over a span of
/// 1e-6, and wrote "800.0"), in scientific notation far from 1. A zero
/// that rounding left negative (a tick at -5.6e-17 of a range from -0.7 to
/// 0.2) reads "0", not "-0".
fn tick_label(v: f64, (step, magnitude): (f64, f64)) -> String {
    // The spacing is {1, 2, 5}·10^m: m, kept from rounding just below.
    let m = (step.log10() + 1e-9).floor();
    let text = if !(step > 0.0 && step.is_finite()) {
        crate::io::readable(v)
    } else if magnitude >= 1e6 || m < -5.0 {
        let digits = (magnitude.log10().floor() - m).clamp(0.0, 15.0) as usize;
        format!("{v:.digits$e}")
    } else {
        let decimals = (-m).max(0.0) as usize;
        format!("{v:.decimals$}")
    };
    match text.strip_prefix('-') {
        Some(magnitude) if magnitude.parse::<f64>() == Ok(0.0) => magnitude.to_string(),
        _ => text,
    }
}

/// The most ticks an axis gets.
const TICKS: usize = 5;

/// One panel over the time range `(t0, t1)` and y range `(y0, y1)`
/// ([`panel_ranges`]).
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    p: &Panel,
    (t0, t1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x_ticks, y_ticks) = (tick_spacing((t0, t1)), tick_spacing((y0, y1)));
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 14))
        .margin(8)
        // Room for the last time tick's text, centred on the right edge.
        .margin_right(18)
        .x_label_area_size(32)
        .y_label_area_size(56)
        .build_cartesian_2d(t0..t1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(p.y_label.as_str())
        .x_labels(TICKS)
        .y_labels(TICKS)
        .x_label_formatter(&|v| tick_label(*v, x_ticks))
        .y_label_formatter(&|v| tick_label(*v, y_ticks))
        .label_style(("sans-serif", 11))
        .light_line_style(WHITE)
        .draw()?;
    for s in &p.series {
        let points = thinned(s, (t0, t1), PANEL_WIDTH as usize);
        let style = line_style(s.file);
        if s.left {
            chart.draw_series(DashedLineSeries::new(points, 6, 4, style))?;
        } else {
            chart.draw_series(LineSeries::new(points, style))?;
        }
    }
    Ok(())
}

/// The report of the trajectory `path` with the reference files `refs`:
/// its SVG text, the panels drawn and the warnings (a reference sharing no
/// column or no time with the trajectory). `columns` says what the files'
/// columns are for the model ([`ModelColumns`]).
pub fn report(
    path: &Path,
    refs: &[PathBuf],
    bilateral: bool,
    columns: &ModelColumns,
) -> Result<(String, Vec<Panel>, Vec<String>), ReportError> {
    let mut files = vec![ReportFile::read(path, columns)?];
    if files[0].table.labels.is_empty() {
        return Err(ReportError::Input {
            file: path.into(),
            reason: "no column but time to plot".into(),
        });
    }
    let span = |t: &StoTable| (t.time[0], t.time[t.time.len() - 1]);
    let (t0, t1) = span(&files[0].table);
    let mut warnings = Vec::new();
    // A trajectory of another model: nothing of it is read as the model's
    // (no angle converted from degrees, no panel of its coordinates).
    let of_model =
        |l: &String| columns.angular.contains(l) || columns.pre_4_names.values().any(|p| p == l);
    if !columns.pre_4_names.is_empty() && !files[0].table.labels.iter().any(of_model) {
        warnings.push(format!(
            "{}: no column names a coordinate, muscle or excitation of the model (--model): a trajectory of another model? Its columns are drawn as written",
            path.display()
        ));
    }
    for r in refs {
        let f = ReportFile::read(r, columns)?;
        let (r0, r1) = span(&f.table);
        if crate::io::same_file(r, path) {
            warnings.push(format!(
                "{}: the reference is the trajectory itself: its lines lie under the trajectory's",
                r.display()
            ));
        } else if !f
            .table
            .labels
            .iter()
            .any(|l| files[0].table.labels.contains(l))
        {
            warnings.push(format!(
                "{}: no column in common with {}: nothing of it is drawn",
                r.display(),
                path.display()
            ));
        } else {
            // References are cut to the trajectory's time span; a line
            // needs two rows in it.
            let inside = f
                .table
                .time
                .iter()
                .filter(|t| (t0..=t1).contains(*t))
                .count();
            if inside < 2 {
                warnings.push(format!(
                    "{}: {inside} of its rows (times {}–{} s) within the time span of {} ({}–{} s): nothing of it is drawn",
                    r.display(),
                    crate::io::readable(r0),
                    crate::io::readable(r1),
                    path.display(),
                    crate::io::readable(t0),
                    crate::io::readable(t1)
                ));
            }
        }
        files.push(f);
    }
    let panels = panels(&files, bilateral, &columns.angular);
    let names: Vec<String> = files.iter().map(|f| f.name.clone()).collect();
    let text = svg(
        &format!("leap report: {}", path.display()),
        &names,
        &panels,
        bilateral,
    )
    .map_err(|e| match e {
        ReportError::Draw(reason) => ReportError::Input {
            file: path.into(),
            reason,
        },
        e => e,
    })?;
    Ok((text, panels, warnings))
}

/// The default report file of a trajectory: `<stem>_report.svg` beside it
/// (Moco's report writes `<stem>_report.pdf`).
pub fn default_output(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "trajectory".into());
    path.with_file_name(format!("{stem}_report.svg"))
}

/// Refuse an output file that is the trajectory or a reference (it would
/// be overwritten by the report), that is not named `.svg` (a `.png` had
/// received SVG text), or whose directory does not exist.
pub fn check_output(output: &Path, trajectory: &Path, refs: &[PathBuf]) -> Result<(), ReportError> {
    let refuse = |reason: String| ReportError::Input {
        file: output.into(),
        reason,
    };
    if let Some(input) = std::iter::once(trajectory)
        .chain(refs.iter().map(PathBuf::as_path))
        .find(|p| crate::io::same_file(output, p))
    {
        return Err(refuse(format!(
            "--output is the input file {}: the report would overwrite it; name another file",
            input.display()
        )));
    }
    if output.is_dir() {
        return Err(refuse(format!(
            "--output is a directory; name the .svg file to write (such as {})",
            output
                .join(default_output(trajectory).file_name().unwrap_or_default())
                .display()
        )));
    }
    let svg = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if !svg {
        return Err(refuse(
            "--output: the report is an SVG page; name the file .svg (a browser prints it to PDF, rsvg-convert turns it into PNG)"
                .into(),
        ));
    }
    let dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(refuse(format!(
            "--output: the directory {} does not exist",
            dir.display()
        )));
    }
    Ok(())
}
