//! OpenSim storage files: `.sto` (STOFileAdapter version 3, as Moco writes
//! them; version 1 read too) and `.mot`, and controls read from them.
//!
//! Formats follow the team's notes (`shared/reference/opensim-conventions.md`
//! §3.1, outside the repository): metadata
//! `key=value` lines sorted by key, `DataType=double`, `version=3`,
//! `OpenSimVersion`, `endheader`, a tab-separated label line starting with
//! `time`, then rows printed with 16 significant digits.
//!
//! With `inDegrees=yes` the values of rotational coordinates are in degrees
//! and their speeds in deg/s (OpenSim's Storage convention); translations,
//! fibre lengths, activations and excitations never are. Which columns are
//! angles depends on the model: [`read_states`] converts them to radians.

use crate::model::Mobilizer;
use crate::ode::StateEquation;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A table of time series, OpenSim style.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StoTable {
    /// First header line (the table's name), if any.
    pub name: Option<String>,
    /// Metadata `key=value` (sorted on writing).
    pub metadata: BTreeMap<String, String>,
    /// Column labels after `time`.
    pub labels: Vec<String>,
    pub time: Vec<f64>,
    /// One row per time, `labels.len()` values each.
    pub rows: Vec<Vec<f64>>,
}

/// A storage file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum StoError {
    /// The OS's error is part of the message (not a `source`, which
    /// `{:#}` would print a second time).
    #[error("{file}: {error}")]
    Io {
        file: PathBuf,
        error: std::io::Error,
    },
    #[error("{file}: line {line}: {reason}")]
    Parse {
        file: PathBuf,
        line: usize,
        reason: String,
    },
    #[error("{file}: column '{column}': {reason}")]
    Column {
        file: PathBuf,
        column: String,
        reason: String,
    },
    #[error("{file}: header '{key}': {reason}")]
    Header {
        file: PathBuf,
        key: String,
        reason: String,
    },
    /// A left leg's column and its right partner's, which the symmetric
    /// system carries as one, differ: named alike, as either may be the
    /// wrong one.
    #[error("{file}: columns '{left}' and '{right}' differ at row {row} (t = {time}): {reason}")]
    Copies {
        file: PathBuf,
        left: String,
        right: String,
        row: usize,
        time: f64,
        reason: String,
    },
    /// Too few data rows.
    #[error(
        "{file}: {rows} data row{s}; at least {needed} {are} needed",
        s = if *rows == 1 { "" } else { "s" },
        are = if *needed == 1 { "is" } else { "are" }
    )]
    Rows {
        file: PathBuf,
        rows: usize,
        needed: usize,
    },
}

/// The lines of `text`, each ended by LF, CRLF or a CR alone (old Mac OS
/// files), as [`str::lines`] gives them for the first two: without their
/// ends, and no empty line after a last end.
fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(text);
    std::iter::from_fn(move || {
        let s = rest.take().filter(|s| !s.is_empty())?;
        let b = s.as_bytes();
        match b.iter().position(|&c| c == b'\n' || c == b'\r') {
            Some(k) => {
                let end = if b[k] == b'\r' && b.get(k + 1) == Some(&b'\n') {
                    k + 2
                } else {
                    k + 1
                };
                rest = Some(&s[end..]);
                Some(&s[..k])
            }
            None => Some(s),
        }
    })
}

/// How many line ends (LF, CRLF or CR alone, as [`text_lines`] reads
/// them) `bytes` holds.
fn line_ends(bytes: &[u8]) -> usize {
    bytes
        .iter()
        .enumerate()
        .filter(|&(k, &c)| c == b'\n' || (c == b'\r' && bytes.get(k + 1) != Some(&b'\n')))
        .count()
}

fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 {
            "Inf".into()
        } else {
            "-Inf".into()
        }
    } else {
        // 16 significant digits, like setprecision(16) in the default format.
        let s = format!("{:.15e}", v);
        let parsed: f64 = s.parse().unwrap_or(v);
        let plain = format!("{parsed}");
        if plain.len() <= 24 {
            plain
        } else {
            s
        }
    }
}

/// The largest |t| a table's time column may hold (s): a day. No movement
/// trial lasts so long; a row beyond it is a typo (a last row at t = 1e300
/// had been analysed as a 1e300 s window, its work printed in 300 digits),
/// and within it every span and step stays finite.
pub const MAX_FILE_TIME_S: f64 = 86_400.0;

impl StoTable {
    /// Write as an STOFileAdapter version-3 file (Moco's format).
    pub fn write_sto(&self, path: &Path) -> Result<(), StoError> {
        let mut out = String::new();
        if let Some(n) = &self.name {
            let _ = writeln!(out, "{n}");
        }
        for (k, v) in &self.metadata {
            let _ = writeln!(out, "{k}={v}");
        }
        let _ = writeln!(out, "DataType=double");
        let _ = writeln!(out, "version=3");
        let _ = writeln!(
            out,
            "OpenSimVersion=4.6 (written by leap {})",
            env!("CARGO_PKG_VERSION")
        );
        let _ = writeln!(out, "endheader");
        self.write_body(&mut out);
        write_output(path, out).map_err(|error| StoError::Io {
            file: path.into(),
            error,
        })
    }

    /// Write as a version-1 motion file (`.mot`), as OpenSim's Storage does.
    pub fn write_mot(&self, path: &Path) -> Result<(), StoError> {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{}",
            self.name.clone().unwrap_or_else(|| "leap".into())
        );
        let _ = writeln!(out, "version=1");
        let _ = writeln!(out, "nRows={}", self.time.len());
        let _ = writeln!(out, "nColumns={}", self.labels.len() + 1);
        let _ = writeln!(
            out,
            "inDegrees={}",
            self.metadata
                .get("inDegrees")
                .map(String::as_str)
                .unwrap_or("no")
        );
        let _ = writeln!(out, "endheader");
        self.write_body(&mut out);
        write_output(path, out).map_err(|error| StoError::Io {
            file: path.into(),
            error,
        })
    }

    fn write_body(&self, out: &mut String) {
        out.push_str("time");
        for l in &self.labels {
            out.push('\t');
            out.push_str(l);
        }
        out.push('\n');
        for (t, row) in self.time.iter().zip(&self.rows) {
            out.push_str(&fmt_value(*t));
            for v in row {
                out.push('\t');
                out.push_str(&fmt_value(*v));
            }
            out.push('\n');
        }
    }

    /// Read a `.sto` or `.mot` file (version 1 or 3; tabs or spaces, a tab
    /// ending the label line and the data lines making no column; lines
    /// ended by LF, CRLF or CR alone (old Mac OS); a UTF-8 byte-order
    /// mark). Values are as in the file: see [`read_states`] for degrees.
    /// A header's `nRows` and `nColumns` (time included) must count the
    /// file's data rows and columns.
    pub fn read(path: &Path) -> Result<Self, StoError> {
        let bytes = read_input(path).map_err(|error| StoError::Io {
            file: path.into(),
            error,
        })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            StoError::Parse {
                file: path.into(),
                line: line_ends(good) + 1,
                reason: "not UTF-8 text (a binary file?)".into(),
            }
        })?;
        Self::parse(&text, path)
    }

    /// Parse the text of a storage file; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, StoError> {
        let perr = |line: usize, reason: String| StoError::Parse {
            file: path.into(),
            line,
            reason,
        };
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.trim().is_empty() {
            return Err(perr(1, "the file is empty".into()));
        }
        // The other files a user has at hand: an OpenSim model or setup
        // file (XML, whose lines hold '=' and would read as header keys),
        // a leap model or study (JSON).
        let other = match text.trim_start().chars().next() {
            Some('<') => Some("an XML file (an OpenSim .osim model or setup file?)"),
            Some('{') => Some("a JSON file (a leap model or study?)"),
            _ => None,
        };
        if let Some(what) = other {
            return Err(perr(
                1,
                format!("{what}, not an OpenSim storage table (.sto or .mot, with a header ending in 'endheader')"),
            ));
        }
        let mut table = StoTable::default();
        let mut lines = text_lines(text).enumerate();
        let mut found_end = false;
        // The value and header line of each key, to name both lines of a
        // key given twice with different values (which one holds is
        // anyone's guess).
        let mut header: BTreeMap<String, (String, usize)> = BTreeMap::new();
        let mut version: Option<String> = None;
        for (i, raw) in lines.by_ref() {
            let line = raw.trim();
            if line == "endheader" {
                found_end = true;
                break;
            }
            if let Some((k, v)) = line.split_once('=') {
                let (k, v) = (k.trim(), v.trim());
                if k == "version" {
                    version = Some(v.to_string());
                }
                if !matches!(k, "DataType" | "version" | "OpenSimVersion") {
                    if let Some((old, line)) = header.get(k).filter(|(old, _)| *old != v) {
                        return Err(perr(
                            i + 1,
                            format!(
                                "header key '{k}' given twice: '{old}' on line {line}, '{v}' here"
                            ),
                        ));
                    }
                    header.insert(k.to_string(), (v.to_string(), i + 1));
                    // The counts are the file's, checked below, not kept:
                    // the writers count the table they write.
                    if !matches!(k, "nRows" | "nColumns") {
                        table.metadata.insert(k.to_string(), v.to_string());
                    }
                }
            } else if i == 0 && !line.is_empty() {
                table.name = Some(line.to_string());
            }
        }
        if !found_end {
            return Err(perr(text_lines(text).count(), "no 'endheader' line".into()));
        }
        table.in_degrees(path)?;
        let (label_line, labels_raw) = loop {
            match lines.next() {
                Some((i, raw)) if raw.trim().is_empty() => {
                    let _ = i;
                    continue;
                }
                // Trimmed as a data line is: a tab at the end of every
                // line is no column.
                Some((i, raw)) => break (i + 1, raw.trim()),
                None => {
                    return Err(perr(
                        text_lines(text).count(),
                        "no column labels after 'endheader'".into(),
                    ))
                }
            }
        };
        let labels: Vec<String> = if labels_raw.contains('\t') {
            labels_raw
                .split('\t')
                .map(|s| s.trim().to_string())
                .collect()
        } else {
            labels_raw.split_whitespace().map(str::to_string).collect()
        };
        if labels.first().map(String::as_str) != Some("time") {
            let first = labels.first().cloned().unwrap_or_default();
            let commas = if first.starts_with("time,") {
                " (columns separated by commas: a storage table's are separated by tabs, as OpenSim writes them)"
            } else {
                ""
            };
            return Err(perr(
                label_line,
                format!("the first column must be 'time', got '{first}'{commas}"),
            ));
        }
        if let Some(k) = labels.iter().position(String::is_empty) {
            return Err(perr(
                label_line,
                format!("column {} has no label (time is column 1)", k + 1),
            ));
        }
        if let Some((first, k)) = first_repeat(&labels) {
            return Err(perr(
                label_line,
                format!(
                    "column '{}' appears twice: columns {} and {} (time is column 1)",
                    labels[k],
                    first + 1,
                    k + 1
                ),
            ));
        }
        // A count the header of a version-1 file declares (OpenSim's
        // Storage writes `nRows` and `nColumns`, time a column, as
        // `write_mot` does) must be the file's: a file cut at a line
        // boundary reads as whole otherwise. From version 2 on, OpenSim's
        // reader ignores them and its tables write them back unchanged
        // after a trim or a new column: not checked there, as OpenSim does.
        let counts_hold = version.as_deref().is_none_or(|v| v == "1");
        let declared = |key: &str| -> Result<Option<usize>, StoError> {
            let Some((v, _)) = header.get(key).filter(|_| counts_hold) else {
                return Ok(None);
            };
            v.parse().map(Some).map_err(|_| StoError::Header {
                file: path.into(),
                key: key.into(),
                reason: format!("'{v}' is not a count"),
            })
        };
        let count_err = |key: &str, reason: String| StoError::Header {
            file: path.into(),
            key: key.into(),
            reason,
        };
        let declared_rows = declared("nRows")?;
        if let Some(n) = declared("nColumns")?.filter(|&n| n != labels.len()) {
            return Err(count_err(
                "nColumns",
                format!(
                    "declares {n} columns (time included), the file has {}",
                    labels.len()
                ),
            ));
        }
        table.labels = labels[1..].to_vec();
        for (i, raw) in lines {
            let line = raw.trim();
            if line.is_empty() {
                continue;
            }
            let cells: Vec<&str> = if line.contains('\t') {
                line.split('\t').map(str::trim).collect()
            } else {
                line.split_whitespace().collect()
            };
            if cells.len() != labels.len() {
                return Err(perr(
                    i + 1,
                    format!("{} values, expected {}", cells.len(), labels.len()),
                ));
            }
            let mut vals = Vec::with_capacity(cells.len());
            for (c, cell) in cells.iter().enumerate() {
                let v: f64 = match *cell {
                    "NaN" | "nan" => f64::NAN,
                    "Inf" | "inf" => f64::INFINITY,
                    "-Inf" | "-inf" => f64::NEG_INFINITY,
                    s => match s.parse::<f64>() {
                        // Digits that parse to an infinity: too large for
                        // a double, to be named as written.
                        Ok(v) if v.is_infinite() && s.bytes().any(|b| b.is_ascii_digit()) => {
                            return Err(perr(
                                i + 1,
                                format!(
                                    "column '{}': '{s}' is not a finite number (it overflows)",
                                    labels[c]
                                ),
                            ))
                        }
                        Ok(v) => v,
                        Err(_) => {
                            return Err(perr(
                                i + 1,
                                format!("column '{}': '{s}' is not a number", labels[c]),
                            ))
                        }
                    },
                };
                vals.push(v);
            }
            table.time.push(vals[0]);
            table.rows.push(vals[1..].to_vec());
        }
        if let Some(n) = declared_rows.filter(|&n| n != table.time.len()) {
            return Err(count_err(
                "nRows",
                format!("declares {n} data rows, the file has {}", table.time.len()),
            ));
        }
        Ok(table)
    }

    /// The values of one column.
    pub fn column(&self, label: &str) -> Option<Vec<f64>> {
        let k = self.labels.iter().position(|l| l == label)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }

    /// Whether the values of rotational coordinates are in degrees: the
    /// header's `inDegrees` (`yes` or `no`, any case); radians without it,
    /// as OpenSim assumes. `path` names the file in errors.
    pub fn in_degrees(&self, path: &Path) -> Result<bool, StoError> {
        match self.metadata.get("inDegrees") {
            None => Ok(false),
            Some(v) if v.eq_ignore_ascii_case("yes") => Ok(true),
            Some(v) if v.eq_ignore_ascii_case("no") => Ok(false),
            Some(v) => Err(StoError::Header {
                file: path.into(),
                key: "inDegrees".into(),
                reason: format!("'{v}' is neither 'yes' nor 'no'"),
            }),
        }
    }

    /// Check that there are at least `min_rows` rows and that time is
    /// finite, within [`MAX_FILE_TIME_S`] of 0 and strictly increasing.
    pub fn check_time(&self, path: &Path, min_rows: usize) -> Result<(), StoError> {
        if self.time.len() < min_rows {
            return Err(StoError::Rows {
                file: path.into(),
                rows: self.time.len(),
                needed: min_rows,
            });
        }
        let time_err = |reason: String| StoError::Column {
            file: path.into(),
            column: "time".into(),
            reason,
        };
        for (k, &t) in self.time.iter().enumerate() {
            if !t.is_finite() {
                return Err(time_err(format!("row {}: {t} is not finite", k + 1)));
            }
            if t.abs() > MAX_FILE_TIME_S {
                return Err(time_err(format!(
                    "row {}: t = {} s lies beyond a day (±{MAX_FILE_TIME_S} s): no movement trial lasts so long (a typo in the time column, or times not measured from the trial's start?)",
                    k + 1,
                    readable(t)
                )));
            }
            if k > 0 && t <= self.time[k - 1] {
                return Err(time_err(format!(
                    "not strictly increasing: row {} has t = {t} after t = {}",
                    k + 1,
                    self.time[k - 1]
                )));
            }
        }
        Ok(())
    }

    /// How many columns a Moco trajectory holds after its states, controls
    /// and input controls: its multipliers, derivatives, slacks and
    /// parameters, in this order at the end (`MocoTrajectory`'s blocks,
    /// counted by its header's `num_*` keys). 0 for a file without those
    /// keys, or whose counts do not add up to its columns.
    pub fn moco_columns_after_controls(&self) -> usize {
        let count = |key: &str| -> Option<usize> {
            match self.metadata.get(key) {
                Some(v) => v.trim().parse().ok(),
                None => Some(0),
            }
        };
        if !(self.metadata.contains_key("num_states") && self.metadata.contains_key("num_controls"))
        {
            return 0;
        }
        let blocks = |keys: &[&str]| -> Option<usize> {
            keys.iter()
                .try_fold(0usize, |sum, k| sum.checked_add(count(k)?))
        };
        let leading = blocks(&["num_states", "num_controls", "num_input_controls"]);
        let trailing = blocks(&[
            "num_multipliers",
            "num_derivatives",
            "num_slacks",
            "num_parameters",
        ]);
        match (leading, trailing) {
            (Some(l), Some(t)) if l.checked_add(t) == Some(self.labels.len()) => t,
            _ => 0,
        }
    }

    /// Check that every value of every column but time (which
    /// [`Self::check_time`] checks) is finite, also in the columns the
    /// caller does not read: a NaN or infinity is refused naming its row,
    /// time and column, as [`Self::finite_columns`] (which runs it) does.
    /// A Moco solution's parameter columns (`num_parameters` in the header)
    /// hold their value in the first row and NaN in every later one, as
    /// `MocoTrajectory` writes them: such a column is not refused.
    pub fn check_finite(&self, path: &Path) -> Result<(), StoError> {
        let moco_parameters = self
            .metadata
            .get("num_parameters")
            .and_then(|v| v.trim().parse::<usize>().ok())
            .is_some_and(|n| n > 0);
        let parameter_column = |k: usize| {
            moco_parameters
                && self.rows.first().is_some_and(|r| r[k].is_finite())
                && self.rows.iter().skip(1).all(|r| r[k].is_nan())
        };
        let exempt: Vec<bool> = (0..self.labels.len()).map(parameter_column).collect();
        for (r, row) in self.rows.iter().enumerate() {
            if let Some(k) = (0..row.len()).find(|&k| !exempt[k] && !row[k].is_finite()) {
                return Err(StoError::Column {
                    file: path.into(),
                    column: self.labels[k].clone(),
                    reason: format!(
                        "row {} (t = {}): {} is not a finite number",
                        r + 1,
                        self.time[r],
                        row[k]
                    ),
                });
            }
        }
        Ok(())
    }

    /// The columns `names`, row by row, all finite; then the other columns
    /// must be finite too ([`Self::check_finite`]): a file's NaN is refused
    /// wherever it is. A missing column is an error whose reason is
    /// `missing` (what the caller needed it for), before any of these.
    pub fn finite_columns(
        &self,
        path: &Path,
        names: &[String],
        missing: &str,
    ) -> Result<Vec<Vec<f64>>, StoError> {
        let cols = names
            .iter()
            .map(|n| {
                self.labels
                    .iter()
                    .position(|l| l == n)
                    .ok_or_else(|| StoError::Column {
                        file: path.into(),
                        column: n.clone(),
                        reason: missing.into(),
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut out = Vec::with_capacity(self.rows.len());
        for (r, row) in self.rows.iter().enumerate() {
            let x: Vec<f64> = cols.iter().map(|&c| row[c]).collect();
            if let Some(k) = x.iter().position(|v| !v.is_finite()) {
                return Err(StoError::Column {
                    file: path.into(),
                    column: names[k].clone(),
                    reason: format!(
                        "row {} (t = {}): {} is not a finite number",
                        r + 1,
                        self.time[r],
                        x[k]
                    ),
                });
            }
            out.push(x);
        }
        self.check_finite(path)?;
        Ok(out)
    }
}

impl StoTable {
    /// Refuse a table in which a column differs from the column it copies,
    /// where the table has both: `pairs` gives (copy, original) labels, a
    /// left leg's column and its right partner's, which the symmetric
    /// system carries as one. They agree within 1e-6 relative (leap
    /// writes both from one value); a row whose original is not finite is
    /// left to the reader of the original to refuse. The refusal
    /// ([`StoError::Copies`]) names both columns and values alike.
    pub fn check_copied_columns<'a>(
        &self,
        path: &Path,
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<(), StoError> {
        self.check_copies(path, pairs.into_iter().map(|(c, o)| (c, o, false)))
    }

    /// [`Self::check_copied_columns`] of pairs each flagged whether its
    /// columns hold degrees: compared as the radians [`read_states`]
    /// converts them to, named with the file's own values, and said to be
    /// in degrees.
    fn check_copies<'a>(
        &self,
        path: &Path,
        pairs: impl IntoIterator<Item = (&'a str, &'a str, bool)>,
    ) -> Result<(), StoError> {
        let index: std::collections::HashMap<&str, usize> = self
            .labels
            .iter()
            .enumerate()
            .map(|(k, l)| (l.as_str(), k))
            .collect();
        let col = |l: &str| index.get(l).copied();
        for (copy, original, degrees) in pairs {
            let (Some(c), Some(o)) = (col(copy), col(original)) else {
                continue;
            };
            if c == o {
                continue;
            }
            let radians = |v: f64| if degrees { v.to_radians() } else { v };
            let units = if degrees {
                " (the file's values, in degrees)"
            } else {
                ""
            };
            for (r, row) in self.rows.iter().enumerate() {
                let (vc, vo) = (row[c], row[o]);
                if copies_differ(radians(vc), radians(vo)) {
                    return Err(StoError::Copies {
                        file: path.into(),
                        left: copy.into(),
                        right: original.into(),
                        row: r + 1,
                        time: self.time[r],
                        reason: format!(
                            "{} and {}{units}; {COPY_MISMATCH_REASON}: give both columns the same values, or leave out the left leg's columns",
                            readable(vc),
                            readable(vo)
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

/// Why `copy_mismatch` refuses a left value, and a storage file's left
/// column ([`StoError::Copies`]) is refused; commands that can read both
/// legs (`--full`) recognise their refusal by it and say so.
pub const COPY_MISMATCH_REASON: &str =
    "the symmetric model gives both legs one value, its right leg's";

/// Why a value `copy` of a left leg's column differs from `original`, its
/// right partner's (labelled `original_label`), which the symmetric system
/// carries for both, if it does: by more than 1e-6 relative. A non-finite
/// original is its own reader's to name.
pub fn copy_mismatch(copy: f64, original: f64, original_label: &str) -> Option<String> {
    copies_differ(copy, original).then(|| {
        format!(
            "{} differs from {original_label} ({}): {COPY_MISMATCH_REASON}; give both columns the same values, or leave out the left leg's columns",
            readable(copy),
            readable(original)
        )
    })
}

/// Whether a left leg's value `copy` differs from `original`, its right
/// partner's, by more than 1e-6 relative; a non-finite original is its
/// own reader's to name.
fn copies_differ(copy: f64, original: f64) -> bool {
    let agree = (copy - original).abs() <= 1e-6 * (1.0 + original.abs());
    original.is_finite() && !agree
}

/// The first label that repeats one before it: (its first index, its
/// index). By a hash map, not a scan of the labels before each: a storage
/// file of 400,000 columns took over a minute that way.
pub fn first_repeat<T: AsRef<str>>(labels: &[T]) -> Option<(usize, usize)> {
    let mut seen = std::collections::HashMap::with_capacity(labels.len());
    for (k, label) in labels.iter().enumerate() {
        if let Some(&first) = seen.get(label.as_ref()) {
            return Some((first, k));
        }
        seen.insert(label.as_ref(), k);
    }
    None
}

/// The largest input file leap reads (1 GiB: some 700,000 rows of a
/// solution of the symmetric jump, 1.4 kB each).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The bytes of an input file (model, study, storage, eval input): a
/// directory or a device (`/dev/zero` would fill the memory) is refused with
/// an error saying so, and so is a file or pipe longer than
/// [`MAX_INPUT_BYTES`].
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let meta = std::fs::metadata(path)?;
    let kind = meta.file_type();
    if let Some(why) = not_readable_kind(&kind) {
        return Err(Error::new(ErrorKind::InvalidInput, why));
    }
    let too_long = || {
        Error::new(
            ErrorKind::InvalidInput,
            format!("longer than {MAX_INPUT_BYTES} bytes, the most leap reads"),
        )
    };
    if kind.is_file() && meta.len() > MAX_INPUT_BYTES {
        return Err(too_long());
    }
    // A pipe has no length to check in advance: read one byte past the limit.
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_long());
    }
    Ok(bytes)
}

/// Why a path of this kind is no input file leap reads: a directory, a
/// device or a socket (a file or a pipe is one).
fn not_readable_kind(kind: &std::fs::FileType) -> Option<&'static str> {
    if kind.is_dir() {
        return Some("is a directory, not a file");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() || kind.is_block_device() || kind.is_socket() {
            return Some("is a device or socket, not a file");
        }
    }
    None
}

/// Why a path written in a study file cannot name a file, if it cannot: a
/// control character (a NUL, a newline, as a JSON `\u0000` or `\n` writes
/// them), which no file name of ours holds and which a message would print
/// raw. The path is quoted with the character escaped.
pub fn path_text_problem(path: &str) -> Option<String> {
    let (k, c) = path.chars().enumerate().find(|(_, c)| c.is_control())?;
    Some(format!(
        "holds the control character U+{:04X} at character {} of {path:?}; remove it",
        c as u32,
        k + 1
    ))
}

/// Why `path` names no input file leap could read, checked before the
/// file is (a study's model and guess): it is missing, a directory, or a
/// device or socket. `None` when it is a file or a pipe.
pub fn input_file_problem(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some("not found".into()),
        Err(e) => Some(format!("cannot be read: {e}")),
        Ok(meta) => not_readable_kind(&meta.file_type()).map(str::to_string),
    }
}

/// [`read_input`] as UTF-8 text.
pub fn read_input_text(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read_input(path)?).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {}; a binary file?)",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// Write an output file whole or not at all: `write` fills a new file
/// beside `path` (synced to disk, with the permissions of the file it
/// replaces), which then replaces `path` by a rename. A failed write, or a
/// panic in `write`, leaves the previous file as it was and removes the new
/// one; a symbolic link at `path` is replaced, not followed: results land in
/// the results directory and nowhere else. (A file that is itself a mount
/// point, as a bind-mounted file in a container, cannot be renamed over: the
/// rename's error says so.)
pub fn write_output_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    use std::io::{Error, ErrorKind};
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    /// The new file, listed in [`PENDING_OUTPUTS`] while it lives:
    /// removed unless the rename took it (`renamed`), and unlisted.
    struct Pending {
        tmp: PathBuf,
        renamed: bool,
    }
    impl Drop for Pending {
        fn drop(&mut self) {
            if !self.renamed {
                let _ = std::fs::remove_file(&self.tmp);
            }
            if let Ok(mut list) = PENDING_OUTPUTS.lock() {
                list.retain(|p| *p != self.tmp);
            }
        }
    }
    let name = path.file_name().ok_or_else(|| {
        Error::new(
            ErrorKind::InvalidInput,
            format!("{}: names no file", path.display()),
        )
    })?;
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let old = std::fs::symlink_metadata(path).ok();
    if old.as_ref().is_some_and(|m| m.is_dir()) {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!("{}: is a directory, not a file", path.display()),
        ));
    }
    // The new file's name: the first 64 characters of the old one's, so
    // that a name near the file system's limit still fits.
    let stem: String = name.to_string_lossy().chars().take(64).collect();
    let mut tries = 0;
    let (tmp, mut file) = loop {
        let tmp = dir.join(format!(
            ".{stem}.{}-{}.tmp",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => break (tmp, f),
            Err(e) if e.kind() == ErrorKind::AlreadyExists && tries < 100 => tries += 1,
            Err(e) => return Err(e),
        }
    };
    if let Ok(mut list) = PENDING_OUTPUTS.lock() {
        list.push(tmp.clone());
    }
    let mut pending = Pending {
        tmp: tmp.clone(),
        renamed: false,
    };
    if let Some(m) = old.filter(|m| m.is_file()) {
        file.set_permissions(m.permissions())?;
    }
    write(&mut file)?;
    file.sync_all()?;
    drop(file);
    std::fs::rename(&tmp, path)?;
    pending.renamed = true;
    Ok(())
}

/// The new files [`write_output_with`] is writing now, so that a process
/// that quits part-way (a repeated Ctrl-C, whose `exit` runs no
/// destructor) can remove them: [`remove_pending_outputs`].
static PENDING_OUTPUTS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// The new files of the writes under way.
pub fn pending_outputs() -> Vec<PathBuf> {
    PENDING_OUTPUTS
        .lock()
        .map(|l| l.clone())
        .unwrap_or_default()
}

/// Remove the new files of the writes under way (their targets keep their
/// previous contents): for a process about to quit part-way through
/// writing its results.
pub fn remove_pending_outputs() {
    for p in pending_outputs() {
        let _ = std::fs::remove_file(p);
    }
}

/// [`write_output_with`] of `bytes`.
pub fn write_output(path: &Path, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    use std::io::Write;
    write_output_with(path, |f| f.write_all(bytes.as_ref()))
}

/// Read a storage file with states of `eq`'s system (a solution, a forward
/// simulation's states) in radians: with `inDegrees=yes` the value and
/// speed columns of its rotational coordinates are converted from degrees
/// (deg/s), the left leg's too; other columns are left as they are. Time
/// must be finite and strictly increasing over at least 2 rows;
/// activations in [0, 1] and fibre lengths positive; a left leg's column,
/// where the symmetric system carries it by its right partner's, equal to
/// that one ([`StoTable::check_copied_columns`]). The values are checked
/// finite by [`StoTable::finite_columns`], which takes the states out
/// (after the check of a missing column, which is the more telling). A
/// file headed `inDegrees=yes` whose angles look like radians is refused
/// ([`check_angle_units`]).
pub fn read_states(eq: &StateEquation, path: &Path) -> Result<StoTable, StoError> {
    let mut t = StoTable::read(path)?;
    t.check_time(path, 2)?;
    let columns = eq.model_state_columns();
    let degrees = t.in_degrees(path)?;
    // A column in degrees: the value or speed of a rotational coordinate.
    let angular = angular_columns(eq);
    let in_degrees = |label: &str| degrees && angular.contains(label);
    // The physical range of the muscle states, as `leap eval` checks it.
    for (k, label) in t.labels.iter().enumerate() {
        if !(label.ends_with("/activation") || label.ends_with("/fiber_length")) {
            continue;
        }
        for (r, row) in t.rows.iter().enumerate() {
            if let Some(reason) = muscle_state_out_of_range(label, row[k]) {
                return Err(StoError::Column {
                    file: path.into(),
                    column: label.clone(),
                    reason: format!("row {} (t = {}): {reason}", r + 1, t.time[r]),
                });
            }
        }
    }
    check_angle_units(&t, path, &angle_ranges(eq), degrees)?;
    // The left leg's columns against their right partners', before the
    // conversion, to name the file's values.
    let names = eq.state_names();
    t.check_copies(
        path,
        columns
            .iter()
            .map(|(l, i)| (l.as_str(), names[*i].as_str(), in_degrees(l))),
    )?;
    to_radians(&mut t, &angular, degrees);
    Ok(t)
}

/// The joint angles of a states file against its header's unit (`degrees`:
/// `inDegrees=yes`). Refused:
/// - headed in degrees, every angle within ±π, one of them beyond 0.2:
///   read in degrees, a movement of less than 3.14° at every joint, no squat
///   or jump (the squat's knee is bent some 80°); read in radians, one. A
///   file in radians with a wrong header, whose angles would be divided by
///   57 (`leap analyze` had printed a jump of −21.7 cm and 1,097 BW from
///   one);
/// - headed in radians (or not headed), an angle beyond ±2π, a whole turn,
///   and outside its coordinate's range (`ranges`, by column): a file in
///   degrees (a guess from one had ended in a numerical error after its
///   projection into the bounds).
pub fn check_angle_units(
    t: &StoTable,
    path: &Path,
    ranges: &HashMap<String, [f64; 2]>,
    degrees: bool,
) -> Result<(), StoError> {
    use std::f64::consts::PI;
    // The angle farthest from zero: (its size, its value, its column); and
    // the farthest beyond a whole turn and its range.
    let mut largest: Option<(f64, f64, &str)> = None;
    let mut turned: Option<(f64, &str)> = None;
    for (k, label) in t.labels.iter().enumerate() {
        let Some(&[lo, hi]) = ranges.get(label.as_str()) else {
            continue;
        };
        for row in &t.rows {
            let v = row[k];
            // A value that is not finite is refused later, by its column.
            if !v.is_finite() {
                continue;
            }
            if largest.is_none_or(|(m, _, _)| v.abs() > m) {
                largest = Some((v.abs(), v, label));
            }
            if v.abs() > 2.0 * PI
                && !(lo..=hi).contains(&v)
                && turned.is_none_or(|(w, _)| v.abs() > w.abs())
            {
                turned = Some((v, label));
            }
        }
    }
    if let (false, Some((v, label))) = (degrees, turned) {
        return Err(StoError::Header {
            file: path.into(),
            key: "inDegrees".into(),
            reason: format!(
                "the header says no (or has no inDegrees, which means radians), but '{label}' reaches {} rad, beyond a whole turn (±2π) and its range: a file in degrees? Write inDegrees=yes",
                readable(v)
            ),
        });
    }
    match largest {
        Some((m, v, label)) if degrees && m > 0.2 && m <= PI => Err(StoError::Header {
            file: path.into(),
            key: "inDegrees".into(),
            reason: format!(
                "the header says yes, but every joint angle lies within ±π (the largest, {} in '{label}', is {:.1}° read as radians): in degrees no joint would move more than 3.14° from zero, where a jumper's squat bends the knee about 80°. A file in radians? Write inDegrees=no",
                readable(v),
                v.to_degrees()
            ),
        }),
        _ => Ok(()),
    }
}

/// Each rotational coordinate's value column (both legs) with its range in
/// the model, for [`check_angle_units`].
pub fn angle_ranges(eq: &StateEquation) -> HashMap<String, [f64; 2]> {
    let nq = eq.nq();
    let angular = angular_columns(eq);
    eq.model_state_columns()
        .into_iter()
        .filter(|(l, _)| l.ends_with("/value") && angular.contains(l))
        .map(|(l, i)| {
            let c = eq.system.coordinates[i % nq];
            (l, eq.model.coordinates[c].range)
        })
        .collect()
}

/// The value and speed columns of the rotational coordinates of `eq`'s
/// model, both legs (`/jointset/<joint>/<coordinate>/value`, `/speed`):
/// the columns that a file with `inDegrees=yes` holds in degrees (deg/s).
pub fn angular_columns(eq: &StateEquation) -> std::collections::HashSet<String> {
    let nq = eq.nq();
    let rotational = rotational_coordinates(eq);
    eq.model_state_columns()
        .into_iter()
        .filter(|(_, i)| *i < 2 * nq && rotational.contains(&(i % nq)))
        .map(|(label, _)| label)
        .collect()
}

/// The model's state columns by the names OpenSim wrote before 4.0, which
/// inverse kinematics (`<coordinate>` columns of a `.mot`), CMC and older
/// states files still carry, each with its absolute path (what Moco's
/// `TabOpUseAbsoluteStateNames` reads): `<coordinate>` for
/// `/jointset/<joint>/<coordinate>/value`, `<coordinate>_u` for its
/// `/speed`, `<muscle>.activation` and `<muscle>.fiber_length` for
/// `/forceset/<muscle>/activation` and `/fiber_length`; and the controls'
/// `<muscle>` and `<muscle>.excitation` (ForwardTool's and CMC's) for
/// `/forceset/<muscle>`.
pub fn pre_4_state_names(eq: &StateEquation) -> std::collections::HashMap<String, String> {
    let controls = eq.model.muscles.iter().flat_map(|m| {
        let name = &m.spec.name;
        let path = format!("/forceset/{name}");
        [
            (name.clone(), path.clone()),
            (format!("{name}.excitation"), path),
        ]
    });
    eq.model_state_columns()
        .into_iter()
        .filter_map(|(path, _)| {
            let segments: Vec<&str> = path.split('/').filter(|s| !s.is_empty()).collect();
            let old = match segments.as_slice() {
                ["jointset", _, c, "value"] => c.to_string(),
                ["jointset", _, c, "speed"] => format!("{c}_u"),
                ["forceset", m, what @ ("activation" | "fiber_length")] => format!("{m}.{what}"),
                _ => return None,
            };
            Some((old, path))
        })
        .chain(controls)
        .collect()
}

/// Rename the columns of `t` that carry a pre-4.0 state name (`names`,
/// [`pre_4_state_names`]) to its absolute path, where `t` has no column of
/// that path already.
pub fn use_absolute_state_names(
    t: &mut StoTable,
    names: &std::collections::HashMap<String, String>,
) {
    let present: std::collections::HashSet<String> = t.labels.iter().cloned().collect();
    for label in &mut t.labels {
        if let Some(path) = names.get(label.as_str()).filter(|p| !present.contains(*p)) {
            *label = path.clone();
        }
    }
}

/// What a file's columns mean for the model: which are rotational
/// coordinates ([`angular_columns`]), and the absolute state paths of
/// pre-4.0 names ([`pre_4_state_names`]).
#[derive(Debug, Clone, Default)]
pub struct ModelColumns {
    pub angular: std::collections::HashSet<String>,
    pub pre_4_names: std::collections::HashMap<String, String>,
    /// The angle columns' coordinate ranges ([`angle_ranges`]): a file's
    /// angles checked against its `inDegrees` ([`check_angle_units`]).
    pub angle_ranges: HashMap<String, [f64; 2]>,
}

impl ModelColumns {
    /// The columns of `eq`'s model, both legs.
    pub fn of(eq: &StateEquation) -> Self {
        ModelColumns {
            angular: angular_columns(eq),
            pre_4_names: pre_4_state_names(eq),
            angle_ranges: angle_ranges(eq),
        }
    }
}

/// With `degrees` (the file's `inDegrees=yes`), convert the columns of `t`
/// named in `angular` ([`angular_columns`]) to radians and mark the table
/// `inDegrees=no`; other columns stay as they are.
pub fn to_radians(t: &mut StoTable, angular: &std::collections::HashSet<String>, degrees: bool) {
    if !degrees {
        return;
    }
    for (k, label) in t.labels.iter().enumerate() {
        if angular.contains(label) {
            for row in &mut t.rows {
                row[k] = row[k].to_radians();
            }
        }
    }
    t.metadata.insert("inDegrees".into(), "no".into());
}

/// `text` (an error message, which may echo its input: a column label of a
/// 50 MB header, a name) bounded to about `MAX_MESSAGE_CHARS` characters
/// for a terminal: its start and end kept (the file and field lead a
/// message, the reason ends it) and the middle left out, with how much.
pub fn bounded_message(text: &str) -> std::borrow::Cow<'_, str> {
    let n = text.chars().count();
    if n <= MAX_MESSAGE_CHARS {
        return text.into();
    }
    let (head, tail) = (MAX_MESSAGE_CHARS * 2 / 3, MAX_MESSAGE_CHARS / 3);
    let start: String = text.chars().take(head).collect();
    let end: String = text.chars().skip(n - tail).collect();
    format!("{start}…[{} characters left out]…{end}", n - head - tail).into()
}

/// The longest message `bounded_message` leaves whole (characters).
pub const MAX_MESSAGE_CHARS: usize = 3000;

/// A number as a message shows it: as written for everyday magnitudes,
/// in exponent form where `{}` would print hundreds of digits.
pub fn readable(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// How far outside [0, 1] a file's activation may lie
/// ([`muscle_state_out_of_range`]).
pub const ACTIVATION_SLACK: f64 = 1e-3;

/// Why a muscle state named `label` (OpenSim's `/activation` or
/// `/fiber_length` path) is outside its physical range, if it is: an
/// activation in [0, 1] to 1e-3 (an explicit integrator's step overshoots
/// the bound a little: `leap simulate --integrator RungeKuttaFeldberg` at
/// 1e-5 writes 1.00009; IPOPT, Moco's solver, relaxes bounds by 1e-8; the
/// SQP projects a guess into its bounds, and the muscle laws clamp the
/// activation as OpenSim's do), a fibre length positive. Other states have
/// no range here.
pub fn muscle_state_out_of_range(label: &str, v: f64) -> Option<String> {
    if label.ends_with("/activation") && !(-ACTIVATION_SLACK..=1.0 + ACTIVATION_SLACK).contains(&v)
    {
        Some(format!(
            "an activation must be in [0, 1], got {}",
            readable(v)
        ))
    } else if label.ends_with("/fiber_length") && (v.is_nan() || v <= 0.0) {
        Some(format!(
            "a fibre length must be positive, got {} m",
            readable(v)
        ))
    } else {
        None
    }
}

/// The system coordinates of `eq` that are angles: a pin's, a translating
/// hinge's (its translation follows the angle) and a planar joint's
/// rotation. Sorted, without repeats (symmetric sides share a q).
pub(crate) fn rotational_coordinates(eq: &StateEquation) -> Vec<usize> {
    let mut qs: Vec<usize> = eq
        .system
        .bodies
        .iter()
        .filter_map(|b| match &b.mobilizer {
            Mobilizer::Planar { q } => Some(q[0]),
            Mobilizer::Pin { q } | Mobilizer::TranslatingHinge { q, .. } => Some(*q),
            Mobilizer::Weld => None,
        })
        .collect();
    qs.sort_unstable();
    qs.dedup();
    qs
}

/// The labels a muscle's excitation column may have: `/forceset/<m>`
/// (Moco), `<m>` or `<m>.excitation` (OpenSim 3 controls).
fn excitation_labels(m: &str) -> [String; 3] {
    [
        format!("/forceset/{m}"),
        m.to_string(),
        format!("{m}.excitation"),
    ]
}

/// The columns of a controls table that look like excitations (labelled
/// `/forceset/<x>`, or without a `/`) but name none of `muscles` (every
/// muscle of the model, both legs): a misspelt muscle, or an actuator the
/// model does not have. Nothing reads them; state columns (a solution's)
/// are not counted, nor a Moco trajectory's columns after its controls
/// ([`StoTable::moco_columns_after_controls`]: multipliers
/// `lambda_cid<k>_p<j>`, slacks and parameters have no `/` either).
pub fn unread_excitation_columns(t: &StoTable, muscles: &[&str]) -> Vec<String> {
    let known: std::collections::HashSet<String> =
        muscles.iter().flat_map(|m| excitation_labels(m)).collect();
    let controls_end = t.labels.len() - t.moco_columns_after_controls();
    t.labels[..controls_end]
        .iter()
        .filter(|l| {
            let control_like = l
                .strip_prefix("/forceset/")
                .map_or(!l.contains('/'), |m| !m.contains('/'));
            control_like && !known.contains(l.as_str())
        })
        .cloned()
        .collect()
}

/// For a missing excitation column: the file's columns that look like
/// excitations of no muscle among `muscles` or their left partners (a
/// misspelt one), as "; columns naming no muscle: 'a', 'b'".
fn unread_columns_note(t: &StoTable, muscles: &[&str]) -> String {
    let left: Vec<String> = muscles
        .iter()
        .filter_map(|m| m.strip_suffix("_r").map(|stem| format!("{stem}_l")))
        .collect();
    let all: Vec<&str> = muscles
        .iter()
        .copied()
        .chain(left.iter().map(String::as_str))
        .collect();
    let unread = unread_excitation_columns(t, &all);
    if unread.is_empty() {
        return String::new();
    }
    let shown: Vec<String> = unread.iter().take(5).map(|l| format!("'{l}'")).collect();
    let more = if unread.len() > 5 {
        format!(" and {} more", unread.len() - 5)
    } else {
        String::new()
    };
    format!("; columns naming no muscle: {}{more}", shown.join(", "))
}

/// Where a controls file lacks muscle `m`'s excitation but holds its
/// activation: a states file given for controls, said so.
fn states_file_note(t: &StoTable, m: &str) -> String {
    let activation = [
        format!("/forceset/{m}/activation"),
        format!("{m}.activation"),
    ];
    match activation.iter().find(|a| t.labels.contains(a)) {
        Some(a) => format!(
            "; the file holds '{a}': a states file? Excitations are read from a controls file (a simulation's forward_controls.sto) or a solution (_solution.sto)"
        ),
        None => String::new(),
    }
}

/// Excitations over time read from a controls file, one column per muscle,
/// linearly interpolated (held constant outside the time range).
#[derive(Debug, Clone)]
pub struct Controls {
    pub time: Vec<f64>,
    /// `values[k][m]`: muscle m at time k.
    pub values: Vec<Vec<f64>>,
}

impl Controls {
    /// Read excitations for `muscles` from an OpenSim controls or Moco
    /// solution file. A muscle's column may be named `/forceset/<m>` (Moco),
    /// `<m>` or `<m>.excitation` (OpenSim 3 controls). Every muscle must
    /// have a column; values must be finite and in [0, 1], and every other
    /// column's finite too ([`StoTable::check_finite`]); time must increase
    /// strictly. A column of a left muscle `<stem>_l` not among
    /// `muscles`, whose right partner `<stem>_r` is (the symmetric system
    /// carries both by the right one), must equal the right one's. A
    /// muscle's excitation in two columns (`/forceset/<m>` and `<m>`) is
    /// refused: one of them would be lost.
    pub fn from_file(path: &Path, muscles: &[&str]) -> Result<Self, StoError> {
        let t = StoTable::read(path)?;
        Self::from_table(&t, path, muscles)
    }

    /// As [`Self::from_file`] for a parsed table.
    pub fn from_table(t: &StoTable, path: &Path, muscles: &[&str]) -> Result<Self, StoError> {
        t.check_time(path, 1)?;
        let mut cols = Vec::with_capacity(muscles.len());
        for m in muscles {
            let names = excitation_labels(m);
            let k = names
                .iter()
                .find_map(|n| t.labels.iter().position(|l| l == n))
                .ok_or_else(|| StoError::Column {
                    file: path.into(),
                    column: format!("/forceset/{m}"),
                    reason: format!(
                        "missing: no excitation column for muscle '{m}' (read as '{}', '{}' or '{}'){}{}",
                        names[0],
                        names[1],
                        names[2],
                        unread_columns_note(t, muscles),
                        states_file_note(t, m)
                    ),
                })?;
            // Two spellings of one muscle's column: one would be lost.
            let given: Vec<&String> = names.iter().filter(|n| t.labels.contains(n)).collect();
            if let [first, second, ..] = given[..] {
                return Err(StoError::Column {
                    file: path.into(),
                    column: second.clone(),
                    reason: format!(
                        "holds the excitation of muscle '{m}', as column '{first}' does: keep one of them"
                    ),
                });
            }
            for (r, row) in t.rows.iter().enumerate() {
                let v = row[k];
                if !v.is_finite() || !(0.0..=1.0).contains(&v) {
                    return Err(StoError::Column {
                        file: path.into(),
                        column: t.labels[k].clone(),
                        reason: format!(
                            "row {} (t = {}): excitation {} is not a number in [0, 1]",
                            r + 1,
                            readable(t.time[r]),
                            readable(v)
                        ),
                    });
                }
            }
            cols.push(k);
        }
        // The columns not read (a solution's states): after the read ones,
        // which say why their values matter.
        t.check_finite(path)?;
        // A left muscle's column, where its right partner's excitation is
        // read for both, must agree with it.
        let mut pairs = Vec::new();
        for (m, &k) in muscles.iter().zip(&cols) {
            let Some(stem) = m.strip_suffix("_r") else {
                continue;
            };
            let left = format!("{stem}_l");
            if muscles.contains(&left.as_str()) {
                continue;
            }
            for copy in excitation_labels(&left) {
                pairs.push((copy, t.labels[k].clone()));
            }
        }
        t.check_copied_columns(path, pairs.iter().map(|(c, o)| (c.as_str(), o.as_str())))?;
        let values = t
            .rows
            .iter()
            .map(|row| cols.iter().map(|&k| row[k]).collect())
            .collect();
        Ok(Controls {
            time: t.time.clone(),
            values,
        })
    }

    /// Check that a run from 0 to `t_max` reads more than one row of a file
    /// of several rows (read from `path`): it must not start at or after
    /// `t_max`, nor end at or before 0. A single row is a constant, held
    /// throughout.
    pub fn check_run(&self, path: &Path, t_max: f64) -> Result<(), StoError> {
        let (Some(&t0), Some(&t1)) = (self.time.first(), self.time.last()) else {
            return Ok(());
        };
        let reason = if self.time.len() < 2 {
            return Ok(());
        } else if t0 >= t_max {
            format!(
                "starts at {} s, not before the simulation's end t_max = {} s: nothing of it would be read but its first row (OpenSim's files are in seconds)",
                readable(t0),
                readable(t_max)
            )
        } else if t1 <= 0.0 {
            format!(
                "ends at {} s, not after the simulation's start at 0 s (the static squat): nothing of it would be read but its last row",
                readable(t1)
            )
        } else {
            return Ok(());
        };
        Err(StoError::Column {
            file: path.into(),
            column: "time".into(),
            reason,
        })
    }

    /// Excitations at time `t` into `out`.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let n = self.time.len();
        if t <= self.time[0] {
            out.copy_from_slice(&self.values[0]);
            return;
        }
        if t >= self.time[n - 1] {
            out.copy_from_slice(&self.values[n - 1]);
            return;
        }
        let k = self.time.partition_point(|&x| x <= t) - 1;
        let w = (t - self.time[k]) / (self.time[k + 1] - self.time[k]);
        for (m, o) in out.iter_mut().enumerate() {
            *o = (1.0 - w) * self.values[k][m] + w * self.values[k + 1][m];
        }
    }
}

/// Whether `a` and `b` are the same existing file (after symbolic links
/// and relative paths are resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// The first of a run's `inputs` (what it is, its path) that is one of the
/// result files `files` the run writes into `dir`, with the reason to
/// refuse it (the run would overwrite or remove it; `instead` says what the
/// user may do). A result file that is a symbolic link is replaced, not
/// written through ([`write_output_with`]), so the results are compared by
/// their own paths, the inputs by what they are.
pub fn input_among_results<'a>(
    inputs: impl IntoIterator<Item = (&'a str, &'a Path)>,
    dir: &Path,
    files: &[String],
    instead: &str,
) -> Option<(&'a Path, String)> {
    // No directory yet: no result file to lose.
    let dir = dir.canonicalize().ok()?;
    inputs.into_iter().find_map(|(what, input)| {
        let real = input.canonicalize().ok()?;
        let r = files.iter().map(|f| dir.join(f)).find(|r| *r == real)?;
        Some((
            input,
            format!(
                "{what} is one of this run's result files ({}), which the run would overwrite or remove; copy it elsewhere, or give the run {instead}",
                r.display()
            ),
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A muscle's column misspelt: the missing muscle's error names the
    /// labels read and the file's column that names no muscle (not the left
    /// leg's columns, which are read as copies).
    #[test]
    fn a_missing_excitation_names_the_misspelt_column() {
        let t = StoTable {
            labels: vec![
                "/forceset/solues_r".into(),
                "/forceset/vasti_r".into(),
                "/forceset/vasti_l".into(),
            ],
            time: vec![0.0],
            rows: vec![vec![0.5, 0.5, 0.5]],
            ..Default::default()
        };
        let e = Controls::from_table(&t, Path::new("c.sto"), &["vasti_r", "soleus_r"])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "c.sto: column '/forceset/soleus_r': missing: no excitation column for muscle 'soleus_r' (read as '/forceset/soleus_r', 'soleus_r' or 'soleus_r.excitation'); columns naming no muscle: '/forceset/solues_r'"
        );
    }

    /// A states file given for controls: its activation column named.
    #[test]
    fn a_states_file_given_for_controls_is_named() {
        let t = StoTable {
            labels: vec![
                "/forceset/soleus_r/activation".into(),
                "/forceset/soleus_r/fiber_length".into(),
            ],
            time: vec![0.0],
            rows: vec![vec![0.5, 0.05]],
            ..Default::default()
        };
        let e = Controls::from_table(&t, Path::new("s.sto"), &["soleus_r"])
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with("the file holds '/forceset/soleus_r/activation': a states file? Excitations are read from a controls file (a simulation's forward_controls.sto) or a solution (_solution.sto)"),
            "{e}"
        );
    }

    /// A Moco solution's multipliers, slacks and parameters carry no `/`
    /// but are no excitations: only a misspelt control is reported. A
    /// header whose counts do not match the columns counts every column.
    #[test]
    fn moco_columns_after_the_controls_are_not_unread_excitations() {
        let text = |states: usize| {
            format!(
                "num_states={states}\nnum_controls=2\nnum_multipliers=1\nnum_derivatives=1\n\
                 num_slacks=1\nnum_parameters=1\nendheader\n\
                 time\t/jointset/hip_r/hip_flexion_r/value\t/forceset/soleus_r\tsolues_r\t\
                 lambda_cid0_p0\t/jointset/hip_r/hip_flexion_r/accel\tgamma_cid0_p0\tmass_scale\n\
                 0\t0.1\t0.5\t0.5\t0\t0\t0\t1.2\n"
            )
        };
        let t = StoTable::parse(&text(1), Path::new("s.sto")).unwrap();
        assert_eq!(t.moco_columns_after_controls(), 4);
        assert_eq!(unread_excitation_columns(&t, &["soleus_r"]), ["solues_r"]);
        let t = StoTable::parse(&text(2), Path::new("s.sto")).unwrap();
        assert_eq!(t.moco_columns_after_controls(), 0);
        assert_eq!(
            unread_excitation_columns(&t, &["soleus_r"]),
            ["solues_r", "lambda_cid0_p0", "gamma_cid0_p0", "mass_scale"]
        );
    }

    #[test]
    fn a_byte_order_mark_is_stripped() {
        let t = StoTable::parse(
            "\u{feff}states\nendheader\ntime\tx\n0\t1\n",
            Path::new("bom.sto"),
        )
        .unwrap();
        assert_eq!(t.name.as_deref(), Some("states"));
        assert_eq!(t.labels, ["x"]);
        assert_eq!(t.rows, [[1.0]]);
    }

    #[test]
    fn duplicate_labels_are_refused_naming_the_label_and_both_columns() {
        let e = StoTable::parse(
            "endheader\ntime\tx\ty\tx\n0\t1\t2\t3\n",
            Path::new("dup.sto"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("dup.sto: line 2:") && e.contains("'x'") && e.contains("columns 2 and 4"),
            "{e}"
        );
    }

    #[test]
    fn in_degrees_is_yes_or_no_in_any_case() {
        for (value, want) in [("yes", true), ("YES", true), ("No", false), ("no", false)] {
            let text = format!("inDegrees={value}\nendheader\ntime\tx\n0\t1\n");
            let t = StoTable::parse(&text, Path::new("a.sto")).unwrap();
            assert_eq!(t.in_degrees(Path::new("a.sto")).unwrap(), want, "{value}");
        }
        // Absent: radians, OpenSim's default.
        let t = StoTable::parse("endheader\ntime\tx\n0\t1\n", Path::new("a.sto")).unwrap();
        assert!(!t.in_degrees(Path::new("a.sto")).unwrap());
        let e = StoTable::parse(
            "inDegrees=true\nendheader\ntime\tx\n0\t1\n",
            Path::new("b.sto"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("b.sto: header 'inDegrees':") && e.contains("'true'"),
            "{e}"
        );
    }

    #[test]
    fn an_empty_file_says_so() {
        let e = StoTable::parse("\u{feff}\n \n", Path::new("e.sto"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "e.sto: line 1: the file is empty");
    }

    /// Up to the bound a message is whole; beyond it, its first two thirds
    /// and last third of the bound in characters (not bytes: 'µ' and '…'
    /// are two and three bytes) with the count of what was left out.
    #[test]
    fn bounded_messages_keep_their_ends_and_count_the_middle() {
        let whole = "µ".repeat(MAX_MESSAGE_CHARS);
        assert_eq!(bounded_message(&whole), whole.as_str());
        let long = format!("head{}tail", "µ".repeat(10_000));
        let b = bounded_message(&long);
        let (head, tail) = (MAX_MESSAGE_CHARS * 2 / 3, MAX_MESSAGE_CHARS / 3);
        let left_out = long.chars().count() - head - tail;
        assert!(b.starts_with("headµ"), "{}", &b[..10]);
        assert!(b.ends_with("µtail"));
        assert!(b.contains(&format!("…[{left_out} characters left out]…")));
        assert_eq!(
            b.chars().count(),
            head + tail
                + format!("…[{left_out} characters left out]…")
                    .chars()
                    .count()
        );
    }
}
