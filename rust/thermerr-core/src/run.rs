//! Measured runs (formats.md, "Measured run"): `time_s` plus `T_*`, `E_*`, `U_*` columns.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::dialect::{rename_columns, Dialect, Rename};
use crate::error::{Error, Result};
use crate::timeaxis::{time_column, IsoClock, TimeKind, TIME_ISO, TIME_S};

/// What to do with missing values (empty cells or `NaN`) in data columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NanPolicy {
    /// The first missing value is an error naming its row and column.
    Error,
    /// Rows with any missing value are dropped.
    Drop,
    /// Missing values are interpolated linearly in time; leading/trailing gaps take the nearest
    /// value.
    Interpolate,
}

impl std::str::FromStr for NanPolicy {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "error" => Ok(NanPolicy::Error),
            "drop" => Ok(NanPolicy::Drop),
            "interpolate" => Ok(NanPolicy::Interpolate),
            other => Err(Error::param(
                "nan",
                format!("must be \"error\", \"drop\" or \"interpolate\", got {other:?}"),
            )),
        }
    }
}

/// The prefixes of the columns a run carries.
pub const PREFIXES: [&str; 3] = ["T_", "E_", "U_"];

/// A validated measured run. Columns keep the file's order.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// Where it came from (a path, or `<DataFrame>`), used in error messages.
    pub source: String,
    pub time_s: Vec<f64>,
    pub names: Vec<String>,
    pub columns: Vec<Vec<f64>>,
    /// Columns that were ignored because their prefix is not one of [`PREFIXES`].
    pub ignored: Vec<String>,
    /// 1-based data-row numbers dropped under [`NanPolicy::Drop`].
    pub dropped_rows: Vec<usize>,
    /// Number of values filled under [`NanPolicy::Interpolate`].
    pub interpolated: usize,
}

/// Largest magnitude a cell of a run may have. Beyond it, squares and sums of squares lose all
/// precision (and above ~1e154 overflow to infinity), so figures and fits would be meaningless;
/// real runs stay many orders of magnitude below (epoch seconds are ~2e9).
pub const MAX_ABS_VALUE: f64 = 1e12;

/// A column's short spikes, bridged by [`Run::bridged`].
#[derive(Clone, Debug, PartialEq)]
pub struct Bridge {
    pub column: String,
    /// The rows bridged (0-based, half-open), in order.
    pub rows: Vec<std::ops::Range<usize>>,
}

impl Bridge {
    /// "T_t8: 1 short spike (11 rows, first at row 3001), each back within 600 s" (rows 1-based,
    /// as the run's errors count them).
    pub fn said(&self) -> String {
        let count: usize = self.rows.iter().map(|r| r.len()).sum();
        format!(
            "{}: {} short spike{} ({count} row{}, first at row {}), each back within {} s",
            self.column,
            self.rows.len(),
            if self.rows.len() == 1 { "" } else { "s" },
            if count == 1 { "" } else { "s" },
            self.rows.first().map_or(0, |r| r.start + 1),
            crate::guard::GAP_FLOOR_S
        )
    }
}

impl Run {
    /// This run with each of `columns` whose failing stretches are all short spikes
    /// ([`crate::guard::short_failures`]: a thermocouple's glitch, a contact loose for a moment,
    /// each back within [`crate::guard::GAP_FLOOR_S`]) bridged by a straight line in time between
    /// the right readings on either side, with what was bridged; `None` when none of them has
    /// such spikes. A column that fails for longer, or to the end, is left as read.
    pub fn bridged(&self, columns: &[&str]) -> Option<(Run, Vec<Bridge>)> {
        let mut out: Option<(Run, Vec<Bridge>)> = None;
        for (k, name) in self.names.iter().enumerate() {
            if !columns.contains(&name.as_str()) {
                continue;
            }
            let Some(rows) = crate::guard::short_failures(&self.columns[k], &self.time_s) else {
                continue;
            };
            let (copy, said) = out.get_or_insert_with(|| (self.clone(), Vec::new()));
            let col = &mut copy.columns[k];
            for r in &rows {
                col[r.clone()].fill(f64::NAN);
            }
            interpolate_gaps(&self.time_s, col);
            said.push(Bridge {
                column: name.clone(),
                rows,
            });
        }
        out
    }

    /// Reads a CSV file. Every refusal names the file, and the row/line and column where there is
    /// one.
    pub fn read_csv(path: &Path, nan: NanPolicy) -> Result<Run> {
        Run::read_csv_with(path, nan, Dialect::default(), &[])
    }

    /// [`Run::read_csv`] with another field delimiter (`b';'`, `b'\t'`, ...) or decimal mark,
    /// and header names mapped to the run format's ([`Rename`]; none: as written).
    pub fn read_csv_with(
        path: &Path,
        nan: NanPolicy,
        dialect: Dialect,
        renames: &[Rename],
    ) -> Result<Run> {
        let file = std::fs::File::open(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Run::from_csv_reader_renamed(file, &path.display().to_string(), nan, dialect, renames)
    }

    /// Reads CSV text from any reader (a file, stdin, bytes in memory): the one parser behind
    /// [`Run::read_csv`]. `source` names the data in every refusal, as the path does for a file.
    pub fn from_csv_reader<R: std::io::Read>(
        reader: R,
        source: &str,
        nan: NanPolicy,
    ) -> Result<Run> {
        Run::from_csv_reader_with(reader, source, nan, Dialect::default())
    }

    /// [`Run::from_csv_reader`] with another field delimiter or decimal mark.
    pub fn from_csv_reader_with<R: std::io::Read>(
        reader: R,
        source: &str,
        nan: NanPolicy,
        dialect: Dialect,
    ) -> Result<Run> {
        Run::from_csv_reader_renamed(reader, source, nan, dialect, &[])
    }

    /// [`Run::from_csv_reader_with`], the header's names mapped by `renames` first
    /// ([`rename_columns`]): every later check and refusal names a column by its new name.
    pub fn from_csv_reader_renamed<R: std::io::Read>(
        mut reader: R,
        source: &str,
        nan: NanPolicy,
        dialect: Dialect,
        renames: &[Rename],
    ) -> Result<Run> {
        let delimiter = dialect.delimiter;
        let file = source.to_string();
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).map_err(|source| Error::Io {
            path: file.clone().into(),
            source,
        })?;
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .delimiter(delimiter)
            .trim(csv::Trim::All)
            .from_reader(bytes);
        let header = rdr
            .headers()
            .map_err(|e| csv_error(&file, bytes, e))?
            .clone();
        let mut names: Vec<String> = header.iter().map(str::to_string).collect();
        let named: Vec<&str> = names.iter().map(String::as_str).collect();
        if let Some(reason) = dialect.one_column_header(&named) {
            // one column whose name holds another delimiter: say so before "no time_s column"
            return Err(Error::Parse {
                file,
                line: Some(1),
                row: None,
                column: None,
                reason,
            });
        }
        rename_columns(&file, &mut names, renames)?;
        let time = time_column(&names);
        let parsed: Vec<bool> = names
            .iter()
            .enumerate()
            .map(|(j, s)| time.is_some_and(|(k, _)| k == j) || is_data_column(s))
            .collect();
        // a `time` column of ISO-8601 date-times (when there is no `time_s`): its cells in seconds
        let mut clock = match time {
            Some((k, TimeKind::Iso)) => Some((k, IsoClock::new())),
            _ => None,
        };
        let mut cells: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
        let mut lines: Vec<u64> = Vec::new();
        let mut record = csv::StringRecord::new();
        // a logger's row of units (`s, °C, µm`) or a second header under the first: the first
        // row reads no number in any data cell (the words added to its refusal)
        let units_row = |row: u64, record: &csv::StringRecord| -> String {
            let no_number = || {
                record
                    .iter()
                    .zip(&parsed)
                    .filter(|(_, p)| **p)
                    .all(|(c, _)| dialect.number(c).is_none_or(f64::is_nan))
            };
            if row == 1 && no_number() {
                ", nor is any cell of the row (a row of units or a second header under the \
                 header? remove it)"
                    .to_string()
            } else {
                String::new()
            }
        };
        let mut row = 0u64;
        // the file's line of each record, counted here from its byte offset: the csv crate's
        // own count is one short after CRLF line ends and blank lines (rust-csv #395, #208)
        let mut lines_to = LineCount::default();
        let mut last_start = None;
        loop {
            match rdr.read_record(&mut record) {
                Ok(false) => break,
                Ok(true) => {}
                Err(e) => return Err(csv_error(&file, bytes, e)),
            }
            row += 1;
            last_start = record.position().map(|p| p.byte() as usize);
            let line = record
                .position()
                .map(|p| lines_to.line_at(bytes, p.byte()))
                .unwrap_or(row + 1);
            for (j, cell) in record.iter().enumerate() {
                if cell.contains(['\n', '\r']) {
                    // a quoted cell over several lines: a run has one sample per line, and a
                    // quote left open (`"1`) would take the samples after it into this cell
                    return Err(Error::Parse {
                        file: file.clone(),
                        line: Some(line),
                        row: Some(row),
                        column: Some(names[j].clone()),
                        reason: format!(
                            "a quoted cell runs over {} lines (a `\"` left open?): a run has one \
                             sample per line",
                            cell.matches('\n').count() + 1
                        ),
                    });
                }
                if !parsed[j] {
                    cells[j].push(f64::NAN);
                    continue;
                }
                if let Some((_, c)) = clock.as_mut().filter(|(k, _)| *k == j) {
                    let v = c.seconds(cell).map_err(|reason| Error::Parse {
                        file: file.clone(),
                        line: Some(line),
                        row: Some(row),
                        column: Some(names[j].clone()),
                        reason: reason + &units_row(row, &record),
                    })?;
                    cells[j].push(v);
                    continue;
                }
                let v = dialect.number(cell).ok_or_else(|| Error::Parse {
                    file: file.clone(),
                    line: Some(line),
                    row: Some(row),
                    column: Some(names[j].clone()),
                    reason: dialect.not_a_number(&names[j], cell) + &units_row(row, &record),
                })?;
                cells[j].push(v);
            }
            lines.push(line);
        }
        // the csv reader takes a quote that is never closed to run to the end of the file: the
        // rest of the file would be one cell, its rows silently gone (only the last record can
        // hold such a quote)
        if let Some(j) =
            last_start.and_then(|b| unclosed_quote(&bytes[b.min(bytes.len())..], delimiter))
        {
            return Err(Error::Parse {
                file,
                line: lines.last().copied(),
                row: Some(row),
                column: names.get(j).cloned(),
                reason: "a quoted cell (`\"`) opened here is never closed: the rest of the file \
                         would be read as this one cell"
                    .to_string(),
            });
        }
        Run::from_columns(&file, names, cells, nan, Some(&lines))
    }

    /// Validates named columns (all of equal length). `lines` maps data rows to file lines for
    /// error messages, when the data came from a file.
    pub fn from_columns(
        source: &str,
        names: Vec<String>,
        columns: Vec<Vec<f64>>,
        nan: NanPolicy,
        lines: Option<&[u64]>,
    ) -> Result<Run> {
        let at = |row: usize, column: &str, reason: String| Error::Parse {
            file: source.to_string(),
            line: lines.and_then(|l| l.get(row).copied()),
            row: Some(row as u64 + 1),
            column: Some(column.to_string()),
            reason,
        };
        let whole = |reason: String| Error::Parse {
            file: source.to_string(),
            line: None,
            row: None,
            column: None,
            reason,
        };
        if names.len() != columns.len() {
            return Err(Error::Shape(format!(
                "{} names for {} columns",
                names.len(),
                columns.len()
            )));
        }
        for (k, name) in names.iter().enumerate() {
            if names[..k].contains(name) {
                return Err(whole(format!("column `{name}` appears twice")));
            }
        }
        let n = columns.first().map_or(0, Vec::len);
        if columns.iter().any(|c| c.len() != n) {
            return Err(Error::Shape("columns of unequal length".into()));
        }
        let Some((t_idx, kind)) = time_column(&names) else {
            return Err(whole(format!(
                "no `{TIME_S}` column (seconds) or `{TIME_ISO}` column (ISO-8601 date-times) \
                 (columns are: {}){RENAME_HINT}",
                names.join(", ")
            )));
        };
        if !names.iter().any(|n| is_data_column(n)) {
            return Err(whole(format!(
                "no column named as data: temperatures `T_*`, errors `E_*`, inputs `U_*` \
                 (columns are: {}){RENAME_HINT}",
                names.join(", ")
            )));
        }
        let t_name = kind.name();
        if n == 0 {
            return Err(whole("no data rows".into()));
        }
        let time = &columns[t_idx];
        for (i, t) in time.iter().enumerate() {
            if !t.is_finite() {
                return Err(at(i, t_name, "time is missing".into()));
            }
            if i > 0 && *t <= time[i - 1] {
                let mut reason = match kind {
                    TimeKind::Seconds => format!(
                        "time is not strictly increasing ({} after {})",
                        t,
                        time[i - 1]
                    ),
                    TimeKind::Iso => format!(
                        "time is not strictly increasing ({} s after the row before)",
                        t - time[i - 1]
                    ),
                };
                let back = time[i - 1] - t;
                if kind == TimeKind::Iso && (3000.0..=3600.0).contains(&back) {
                    // a local clock set back an hour: the end of daylight saving time
                    reason.push_str(
                        ": an hour back (a local clock leaving daylight saving time? write the \
                         times in UTC or with their offset, such as 2026-10-25T02:00:15+01:00)",
                    );
                } else if *t <= time[0] {
                    reason.push_str(&format!(
                        ", back to the first row's: {}",
                        crate::guard::ONE_RUN
                    ));
                } else if columns.iter().all(|c| {
                    let (a, b) = (c[i], c[i - 1]);
                    a == b || (a.is_nan() && b.is_nan())
                }) {
                    reason.push_str(
                        ": the row repeats the one before it in every column (a logger that \
                         wrote it twice? remove one of them)",
                    );
                }
                return Err(at(i, t_name, reason));
            }
        }
        let mut keep_names = Vec::new();
        let mut keep_cols = Vec::new();
        let mut ignored = Vec::new();
        for (k, (name, col)) in names.iter().zip(&columns).enumerate() {
            if k == t_idx {
                continue;
            }
            if is_data_column(name) {
                keep_names.push(name.clone());
                keep_cols.push(col.clone());
            } else {
                ignored.push(name.clone());
            }
        }
        for (name, col) in std::iter::once((t_name, time))
            .chain(keep_names.iter().map(String::as_str).zip(keep_cols.iter()))
        {
            if let Some(i) = col.iter().position(|v| v.abs() > MAX_ABS_VALUE) {
                return Err(at(
                    i,
                    name,
                    format!(
                        "{:e} is beyond ±{MAX_ABS_VALUE:e}: no temperature, error, input or time \
                         in seconds is that large (is the unit right?)",
                        col[i]
                    ),
                ));
            }
        }
        let mut time = time.clone();
        if kind == TimeKind::Iso {
            // date-times are read as seconds since the epoch: the run's clock starts at its first row
            let t0 = time[0];
            time.iter_mut().for_each(|t| *t -= t0);
        }
        let mut dropped_rows = Vec::new();
        let mut interpolated = 0;
        match nan {
            NanPolicy::Error => {
                for i in 0..n {
                    for (name, col) in keep_names.iter().zip(&keep_cols) {
                        if col[i].is_nan() {
                            return Err(at(
                                i,
                                name,
                                "missing value (to accept gaps: nan=\"interpolate\" fills each linearly in time, nan=\"drop\" removes its row; --nan on the command line)"
                                    .into(),
                            ));
                        }
                    }
                }
            }
            NanPolicy::Drop => {
                let keep: Vec<bool> = (0..n)
                    .map(|i| keep_cols.iter().all(|c| !c[i].is_nan()))
                    .collect();
                dropped_rows = (0..n).filter(|&i| !keep[i]).map(|i| i + 1).collect();
                if dropped_rows.len() == n {
                    let empty: Vec<String> = keep_names
                        .iter()
                        .zip(&keep_cols)
                        .filter(|(_, c)| c.iter().all(|v| v.is_nan()))
                        .map(|(name, _)| format!("`{name}`"))
                        .collect();
                    return Err(whole(if empty.is_empty() {
                        "every row has a missing value: nothing left after dropping".into()
                    } else {
                        format!(
                            "every row has a missing value: nothing left after dropping ({} {} no values at all: a sensor not connected? remove {} from the file)",
                            empty.join(", "),
                            if empty.len() == 1 { "has" } else { "have" },
                            if empty.len() == 1 { "that column" } else { "those columns" },
                        )
                    }));
                }
                time = select(&time, &keep);
                keep_cols = keep_cols.iter().map(|c| select(c, &keep)).collect();
            }
            NanPolicy::Interpolate => {
                for (name, col) in keep_names.iter().zip(keep_cols.iter_mut()) {
                    let filled = interpolate_gaps(&time, col);
                    if filled == usize::MAX {
                        return Err(whole(format!(
                            "column `{name}` has no values at all (a sensor not connected?): remove the column from the file"
                        )));
                    }
                    interpolated += filled;
                }
            }
        }
        Ok(Run {
            source: source.to_string(),
            time_s: time,
            names: keep_names,
            columns: keep_cols,
            ignored,
            dropped_rows,
            interpolated,
        })
    }

    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The column called `name`, or an error listing the columns there are.
    pub fn column(&self, name: &str) -> Result<&[f64]> {
        if name == "time_s" {
            return Ok(&self.time_s);
        }
        self.names
            .iter()
            .position(|s| s == name)
            .map(|k| self.columns[k].as_slice())
            .ok_or_else(|| Error::MissingColumn {
                file: self.source.clone(),
                column: name.to_string(),
                available: self.names.join(", "),
            })
    }

    /// Names of the columns that start with `prefix`, in file order.
    pub fn names_with_prefix(&self, prefix: &str) -> Vec<String> {
        self.names
            .iter()
            .filter(|s| s.starts_with(prefix))
            .cloned()
            .collect()
    }

    /// The named columns as a row-major `len × names.len()` matrix.
    pub fn matrix(&self, names: &[String]) -> Result<Vec<f64>> {
        let cols: Vec<&[f64]> = names
            .iter()
            .map(|s| self.column(s))
            .collect::<Result<_>>()?;
        let mut out = Vec::with_capacity(self.len() * cols.len());
        for i in 0..self.len() {
            out.extend(cols.iter().map(|c| c[i]));
        }
        Ok(out)
    }
}

fn select(v: &[f64], keep: &[bool]) -> Vec<f64> {
    v.iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(x, _)| *x)
        .collect()
}

/// The `time` column of a table already in memory (a DataFrame's strings), ISO-8601 date-times
/// read as the CSV reader reads them, in seconds since the epoch (an empty cell is `NaN`, which
/// [`Run::from_columns`] refuses as a missing time); a refusal names `source`, the row and the
/// column.
pub fn iso_seconds<S: AsRef<str>>(source: &str, cells: &[S]) -> Result<Vec<f64>> {
    let mut clock = IsoClock::new();
    cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            clock.seconds(c.as_ref()).map_err(|reason| Error::Parse {
                file: source.to_string(),
                line: None,
                row: Some(i as u64 + 1),
                column: Some(TIME_ISO.to_string()),
                reason,
            })
        })
        .collect()
}

/// Whether a column is data (`T_`, `E_` or `U_` and a name); every other column but the time is
/// ignored.
pub fn is_data_column(name: &str) -> bool {
    PREFIXES
        .iter()
        .any(|p| name.starts_with(p) && name.len() > p.len())
}

/// What a refusal of a file's column names adds: how to map a logger's names.
const RENAME_HINT: &str = "; map a logger's names with --rename 'OLD=NEW' (Python: \
     read_run(..., rename=[...])), e.g. 'Time (s)=time_s' 'Temp * (°C)=T_*' 'Disp * (um)=E_*'";

/// Rows of a held-out run found among the training run's, at one offset, before it is refused
/// ([`check_unseen`]).
pub const SHARED_ROWS_MIN: usize = 10;
/// A row that repeats more often than this in the training run (an idle machine's plateau on a
/// coarse logger) places nothing: it is not looked for.
const SHARED_ROW_REPEATS: usize = 8;
/// Offsets walked row by row for a stretch alike, those where most changing rows matched.
const SHARED_OFFSETS_TRIED: usize = 4;

/// Refuses a held-out run that holds rows of the training run: a stretch of its consecutive
/// rows, [`SHARED_ROWS_MIN`] or more of them differing from the row before, reads in every
/// column both runs have exactly as a stretch of the training run's (a piece cut from the
/// training log, its clock kept or restarted). Its "held-out" figures would be scored on rows
/// the fit trains on, and, taken as a run of its own from its first readings, scored wrongly
/// besides. Both runs' `cols` are the same columns, in one order ([`Logged`]). Two runs of one
/// machine on a coarse logger pass through the same readings, but not row after row for ten
/// changes; a piece cut out and resampled is not recognised. Then [`check_interleaved`]. One
/// line naming the held-out file, its rows and the training run's.
pub fn check_unseen(train: Logged<'_>, held: Logged<'_>) -> Result<()> {
    check_shared(train, held)?;
    check_interleaved(train, held)
}

/// A run as [`check_unseen`] reads it: its name, its clock (s) and its columns (the time not
/// among them).
#[derive(Clone, Copy)]
pub struct Logged<'a> {
    pub source: &'a str,
    pub time: &'a [f64],
    pub cols: &'a [&'a [f64]],
}

/// Refuses a held-out run whose rows sit between the training run's on its clock: at least
/// half its rows, and [`SHARED_ROWS_MIN`] or more, each differing from the row before, fall on
/// the training run's clock at or between two of its consecutive samples (no more than
/// [`INTERLEAVE_GAP_STEPS`] of its sampling steps apart) and read, in every column both runs
/// have, within [`INTERLEAVE_SLACK`] of that column's typical step (the median change between
/// the training run's consecutive rows that change) of the range of those two samples. That is
/// a log split by rows taken in turn (odd and even rows, every third row held out, a thinned
/// copy): each held-out row's neighbours on either side are training rows, so its figures say
/// little of a run the fit has not seen (time series are validated in time order: a later
/// stretch or another run). A clock kept from the log is recognised (or one restarted in step
/// with it); another run on the same clock (a logger's time of day) reads otherwise in some
/// column within a few rows: on the real 46-h run, no row of one quarter read so beside another
/// quarter's on one clock, where 98 % of the odd rows did beside the even ones.
fn check_interleaved(tr: Logged<'_>, ho: Logged<'_>) -> Result<()> {
    let (train_time, train, held_time, held) = (tr.time, tr.cols, ho.time, ho.cols);
    let (nt, nh) = (train_time.len(), held_time.len());
    if train.is_empty() || train.len() != held.len() || nt < 2 || nh < SHARED_ROWS_MIN {
        return Ok(());
    }
    let Some(step) = crate::timeaxis::median_step(train_time) else {
        return Ok(());
    };
    // a column's typical step: the median change between consecutive rows that change (a
    // logger's resolution where most rows repeat)
    let median = |mut v: Vec<f64>| -> f64 {
        v.retain(|x| x.is_finite());
        if v.is_empty() {
            return 0.0;
        }
        let k = v.len() / 2;
        *v.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let typical: Vec<f64> = train
        .iter()
        .map(|c| {
            median(
                c.windows(2)
                    .map(|w| (w[1] - w[0]).abs())
                    .filter(|d| *d > 0.0)
                    .collect(),
            )
        })
        .collect();
    // the held-out row's training neighbours on the clock: (i, i) on a shared stamp, (i, i + 1)
    // between two samples one step or so apart
    let around = |tau: f64| -> Option<(usize, usize)> {
        let i = train_time.partition_point(|&t| t <= tau).checked_sub(1)?;
        if train_time[i] == tau {
            return Some((i, i));
        }
        (i + 1 < nt && train_time[i + 1] - train_time[i] <= INTERLEAVE_GAP_STEPS * step)
            .then_some((i, i + 1))
    };
    let within = |j: usize, (a, b): (usize, usize)| {
        train.iter().zip(held).zip(&typical).all(|((tc, hc), &ty)| {
            let (lo, hi) = (tc[a].min(tc[b]), tc[a].max(tc[b]));
            let (v, slack) = (hc[j], INTERLEAVE_SLACK * ty);
            v.is_nan() || (lo - slack <= v && v <= hi + slack)
        })
    };
    let changes = |j: usize| j == 0 || held.iter().any(|c| c[j].to_bits() != c[j - 1].to_bits());
    let mut seen: Vec<(usize, (usize, usize))> = Vec::new(); // (held row, training rows)
    for j in (0..nh).filter(|&j| changes(j)) {
        if let Some(ab) = around(held_time[j]).filter(|&ab| within(j, ab)) {
            seen.push((j, ab));
        }
    }
    if seen.len() < SHARED_ROWS_MIN || 2 * seen.len() < nh {
        return Ok(());
    }
    let (first, last) = (seen[0], seen[seen.len() - 1]);
    Err(Error::Parse {
        file: ho.source.to_string(),
        line: None,
        row: None,
        column: None,
        reason: format!(
            "{} of its {nh} rows (rows {}-{}) fall between rows {}-{} of {} on its clock and read as they do (in all {} columns both have, within {INTERLEAVE_SLACK} typical steps): rows taken from the training log in turn (odd and even rows, or a thinned copy), so every held-out row has training rows beside it; hold out a later stretch of the log or a run of its own (time series are validated in time order)",
            seen.len(),
            first.0 + 1,
            last.0 + 1,
            first.1 .0 + 1,
            last.1 .1 + 1,
            tr.source,
            train.len(),
        ),
    })
}

/// A held-out row may sit this many of the training run's sampling steps from the training
/// rows either side of it on the clock ([`check_interleaved`]): one step for odd and even rows,
/// two for every third row held out, and a logger's jitter.
const INTERLEAVE_GAP_STEPS: f64 = 3.5;
/// A held-out row reads within this many typical steps of its training neighbours' range, in
/// every column ([`check_interleaved`]): a noisy reading between two is not always inside their
/// range.
const INTERLEAVE_SLACK: f64 = 3.0;

/// The first part of [`check_unseen`]: a stretch of the training run's rows, at one offset.
fn check_shared(tr: Logged<'_>, ho: Logged<'_>) -> Result<()> {
    let (train_source, train, held_source, held) = (tr.source, tr.cols, ho.source, ho.cols);
    let (nt, nh) = (
        train.first().map_or(0, |c| c.len()),
        held.first().map_or(0, |c| c.len()),
    );
    if train.is_empty() || train.len() != held.len() || nh < SHARED_ROWS_MIN {
        return Ok(());
    }
    // a row's key: its values' bits, with -0.0 as 0.0 and every NaN as one
    let key = |cols: &[&[f64]], r: usize| -> Vec<u64> {
        cols.iter()
            .map(|c| match c[r] {
                v if v.is_nan() => f64::NAN.to_bits(),
                0.0 => 0, // and -0.0
                v => v.to_bits(),
            })
            .collect()
    };
    let train_keys: Vec<Vec<u64>> = (0..nt).map(|r| key(train, r)).collect();
    let held_keys: Vec<Vec<u64>> = (0..nh).map(|r| key(held, r)).collect();
    let mut at: std::collections::HashMap<&[u64], Vec<usize>> = Default::default();
    for (r, k) in train_keys.iter().enumerate() {
        at.entry(k).or_default().push(r);
    }
    // offsets (training row - held row) at which changing rows read alike, with how many
    let changes = |keys: &[Vec<u64>], j: usize| j == 0 || keys[j] != keys[j - 1];
    let mut found: std::collections::HashMap<isize, usize> = Default::default();
    for j in (0..nh).filter(|&j| changes(&held_keys, j)) {
        if let Some(rows) = at
            .get(held_keys[j].as_slice())
            .filter(|r| r.len() <= SHARED_ROW_REPEATS)
        {
            for &i in rows {
                *found.entry(i as isize - j as isize).or_default() += 1;
            }
        }
    }
    // the offsets where most read alike (a piece cut out reads alike at one offset nearly
    // everywhere; a coarse logger's chance matches spread over many), best first
    let mut offsets: Vec<(usize, isize)> = found
        .into_iter()
        .filter(|&(_, n)| n >= SHARED_ROWS_MIN)
        .map(|(d, n)| (n, d))
        .collect();
    offsets.sort_unstable_by_key(|&(n, d)| (std::cmp::Reverse(n), d));
    let offsets = offsets
        .into_iter()
        .take(SHARED_OFFSETS_TRIED)
        .map(|(_, d)| d);
    // at each, the longest stretch of consecutive rows alike: (changing rows, first, last, d)
    let alike = |j: usize, d: isize| {
        let i = j as isize + d;
        i >= 0 && i < nt as isize && held_keys[j] == train_keys[i as usize]
    };
    let mut best: Option<(usize, usize, usize, isize)> = None;
    for d in offsets {
        let mut j = 0;
        while j < nh {
            if !alike(j, d) {
                j += 1;
                continue;
            }
            let (first, mut n) = (j, 0);
            while j < nh && alike(j, d) {
                n += usize::from(j == first || changes(&held_keys, j));
                j += 1;
            }
            if n >= SHARED_ROWS_MIN && best.is_none_or(|b| n > b.0) {
                best = Some((n, first, j - 1, d));
            }
        }
    }
    let Some((_, first, end, d)) = best else {
        return Ok(());
    };
    let row = |j: usize| (j as isize + d) as u64 + 1;
    Err(Error::Parse {
        file: held_source.to_string(),
        line: None,
        row: None,
        column: None,
        reason: format!(
            "rows {}-{} are rows {}-{} of {train_source} (alike row for row in all {} columns both have), which the fit trains on: held-out figures need rows the fit has not seen; hold out a run of its own, or cut these rows from {train_source}",
            first + 1,
            end + 1,
            row(first),
            row(end),
            train.len(),
        ),
    })
}

/// Lines of a text up to a byte offset, counted incrementally for offsets that only grow.
#[derive(Default)]
struct LineCount {
    scanned: usize,
    newlines: u64,
}

impl LineCount {
    /// The 1-based line of the record the csv reader says starts at `offset` of `bytes`: the
    /// first byte there that ends no line (the reader's offset can sit on the LF of the
    /// previous CRLF, or before blank lines).
    fn line_at(&mut self, bytes: &[u8], offset: u64) -> u64 {
        let mut end = (offset as usize).min(bytes.len());
        while end < bytes.len() && matches!(bytes[end], b'\r' | b'\n') {
            end += 1;
        }
        if end < self.scanned {
            *self = LineCount::default();
        }
        self.newlines += bytes[self.scanned..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count() as u64;
        self.scanned = end;
        self.newlines + 1
    }
}

/// The field (0-based) of the record at the start of `bytes` whose quote is still open at the
/// end of `bytes`, if any: a quote opens a field only as its first byte (as the csv reader reads
/// it), `""` inside is a quote, and the record ends at a line end outside quotes.
fn unclosed_quote(bytes: &[u8], delimiter: u8) -> Option<usize> {
    let mut i = bytes
        .iter()
        .take_while(|&&b| matches!(b, b'\r' | b'\n'))
        .count();
    let (mut field, mut at_start, mut quoted) = (0usize, true, false);
    while i < bytes.len() {
        let b = bytes[i];
        if quoted {
            if b == b'"' {
                if bytes.get(i + 1) == Some(&b'"') {
                    i += 2;
                    continue;
                }
                quoted = false;
            }
        } else if at_start && b == b'"' {
            quoted = true;
        } else if b == delimiter {
            field += 1;
            at_start = true;
            i += 1;
            continue;
        } else if matches!(b, b'\r' | b'\n') {
            return None;
        }
        at_start = false;
        i += 1;
    }
    quoted.then_some(field)
}

fn csv_error(file: &str, bytes: &[u8], e: csv::Error) -> Error {
    let line = e
        .position()
        .map(|p| LineCount::default().line_at(bytes, p.byte()));
    let reason = match e.kind() {
        csv::ErrorKind::Utf8 { err, .. } => {
            format!("not valid UTF-8 (field {})", err.field() + 1)
        }
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("{len} fields where the header has {expected_len}"),
        csv::ErrorKind::Io(err) => err.to_string(),
        _ => e.to_string(),
    };
    Error::Parse {
        file: file.to_string(),
        line,
        // the header is record 0
        row: e.position().map(|p| p.record()).filter(|&r| r > 0),
        column: None,
        reason,
    }
}

/// Fills NaN gaps in place, linear in `t`. Returns how many values it filled, or `usize::MAX`
/// when the column has no value at all.
fn interpolate_gaps(t: &[f64], v: &mut [f64]) -> usize {
    let known: Vec<usize> = (0..v.len()).filter(|&i| !v[i].is_nan()).collect();
    if known.is_empty() {
        return usize::MAX;
    }
    let mut filled = 0;
    for i in 0..v.len() {
        if !v[i].is_nan() {
            continue;
        }
        filled += 1;
        let after = known.partition_point(|&k| k < i);
        v[i] = match (after.checked_sub(1).map(|a| known[a]), known.get(after)) {
            (Some(a), Some(&b)) => lerp(t[a], v[a], t[b], v[b], t[i]),
            (Some(a), None) => v[a],
            (None, Some(&b)) => v[b],
            (None, None) => unreachable!("known is non-empty"),
        };
    }
    filled
}

/// The value at `t` on the line through `(ta, va)` and `(tb, vb)`, `ta < t < tb`, all finite.
/// Finite however far apart the values are: `vb - va` or `tb - ta` can overflow to infinity
/// (1e308 and -1e308), so the weight is taken from halved times when the span overflows, and
/// the values are mixed as a convex combination, kept within `[min(va, vb), max(va, vb)]`
/// against rounding.
fn lerp(ta: f64, va: f64, tb: f64, vb: f64, t: f64) -> f64 {
    let span = tb - ta;
    let w = if span.is_finite() {
        (t - ta) / span
    } else {
        (t / 2.0 - ta / 2.0) / (tb / 2.0 - ta / 2.0)
    };
    let w = w.clamp(0.0, 1.0);
    let v = va * (1.0 - w) + vb * w;
    v.clamp(va.min(vb), va.max(vb))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    #[allow(clippy::single_range_in_vec_init)] // a list of row ranges that holds one
    fn only_the_named_columns_short_spikes_are_bridged_on_a_straight_line() {
        let n = 400;
        let time_s: Vec<f64> = (0..n).map(|i| 15.0 * i as f64).collect();
        let warm: Vec<f64> = time_s
            .iter()
            .map(|t| 20.0 + 5.0 * (1.0 - (-t / 3600.0).exp()))
            .collect();
        let mut spiky = warm.clone();
        spiky[200] = 1372.0;
        spiky[201] = 1372.0;
        let mut open = warm.clone();
        for v in &mut open[300..] {
            *v = -200.0;
        }
        let run = Run {
            source: "r.csv".into(),
            time_s: time_s.clone(),
            names: vec!["T_a".into(), "T_b".into(), "T_c".into()],
            columns: vec![spiky.clone(), open.clone(), spiky.clone()],
            ignored: Vec::new(),
            dropped_rows: Vec::new(),
            interpolated: 0,
        };
        // T_c is not asked for, T_b fails to the end: only T_a is bridged
        let (mended, said) = run.bridged(&["T_a", "T_b"]).unwrap();
        assert_eq!(
            said,
            vec![Bridge {
                column: "T_a".into(),
                rows: vec![200..202]
            }]
        );
        assert_eq!(
            said[0].said(),
            "T_a: 1 short spike (2 rows, first at row 201), each back within 600 s"
        );
        let a = &mended.columns[0];
        for k in 200..202 {
            let w = (time_s[k] - time_s[199]) / (time_s[202] - time_s[199]);
            assert!((a[k] - (warm[199] + w * (warm[202] - warm[199]))).abs() < 1e-12);
        }
        assert_eq!(a[..200], warm[..200]);
        assert_eq!(mended.columns[1], open);
        assert_eq!(mended.columns[2], spiky);
        assert!(run.bridged(&["T_b", "T_c_missing"]).is_none());
    }

    fn write(text: &[u8]) -> tempfile_path::TempPath {
        tempfile_path::TempPath::with(text)
    }

    mod tempfile_path {
        pub struct TempPath(pub std::path::PathBuf);
        impl TempPath {
            pub fn with(text: &[u8]) -> Self {
                use std::sync::atomic::{AtomicUsize, Ordering};
                static N: AtomicUsize = AtomicUsize::new(0);
                let p = std::env::temp_dir().join(format!(
                    "thermerr-run-test-{}-{}.csv",
                    std::process::id(),
                    N.fetch_add(1, Ordering::SeqCst)
                ));
                let mut f = std::fs::File::create(&p).unwrap();
                super::Write::write_all(&mut f, text).unwrap();
                TempPath(p)
            }
        }
        impl Drop for TempPath {
            fn drop(&mut self) {
                let _ = std::fs::remove_file(&self.0);
            }
        }
    }

    fn read_err(text: &[u8], delimiter: u8) -> String {
        Run::from_csv_reader_with(
            text,
            "t.csv",
            NanPolicy::Error,
            Dialect {
                delimiter,
                ..Dialect::default()
            },
        )
        .unwrap_err()
        .to_string()
    }

    fn err(text: &[u8], nan: NanPolicy) -> String {
        let p = write(text);
        Run::read_csv(&p.0, nan).unwrap_err().to_string()
    }

    #[test]
    fn a_quote_never_closed_is_refused_not_read_as_the_rest_of_the_file() {
        // found by the property test: the csv reader ran the quote to the end of the file and
        // the rows after it were gone (a note column), or the cell read as the number after it
        let e = read_err(b"time_s,note\n1.0,0.0\n4.0,\"1\n\n5.0,0.0\n", b',');
        assert!(
            e.contains("t.csv")
                && e.contains("line 3")
                && e.contains("note")
                && e.contains("one sample per line"),
            "{e}"
        );
        let e = read_err(b"time_s,T_a\n\n1.0,\"1", b',');
        assert!(e.contains("T_a") && e.contains("never closed"), "{e}");
        // a quote that closes lines later takes the samples between into one cell
        let e = read_err(b"time_s,note,T_a\n1,\"1,2\n2,x,3\n3,\"y\",4\n", b',');
        assert!(
            e.contains("line 2") && e.contains("note") && e.contains("runs over 3 lines"),
            "{e}"
        );
        let e = read_err(b"time_s;note;T_a\n1;\"a\r\nb\";2\n2;x;3\n", b';');
        assert!(e.contains("one sample per line"), "{e}");
        // quotes that close, escaped quotes and a quote inside an unquoted cell are fine
        for text in [
            &b"time_s,note,T_a\n1,\"a, \"\"b\"\"\",2\n2,x,3\n"[..],
            &b"time_s,note,T_a\n1,12\",2\n2,x,3\n"[..],
        ] {
            let r = Run::from_csv_reader_with(text, "t.csv", NanPolicy::Error, Dialect::default())
                .unwrap();
            assert_eq!(r.len(), 2);
        }
        assert_eq!(unclosed_quote(b"1,\"a\"\"\"\n2,3", b','), None);
        assert_eq!(unclosed_quote(b"1,\"a\"\"\n2,3", b','), Some(1));
        assert_eq!(unclosed_quote(b"\n1,2,\"a\n\n3", b','), Some(2));
    }

    /// A row of units under the header: the refusal says what it looks like; one bad cell in the
    /// first row is only that cell.
    #[test]
    fn a_row_of_units_under_the_header_is_named_as_such() {
        let e = err(b"time_s,T_a,E_z\ns,degC,um\n0,20,0\n", NanPolicy::Error);
        assert!(
            e.contains("row 1, column `time_s`: \"s\" is not a number, nor is any cell of the row (a row of units"),
            "{e}"
        );
        let e = err(b"time_s,T_a,E_z\n0,x,0\n15,21,0\n", NanPolicy::Error);
        assert!(
            e.contains("\"x\" is not a number") && !e.contains("units"),
            "{e}"
        );
        let e = err(
            b"time,T_a,E_z\ndate,degC,\n2025-03-04T08:00:00,20,0\n",
            NanPolicy::Error,
        );
        assert!(
            e.contains("row 1, column `time`: ") && e.contains("a row of units"),
            "{e}"
        );
    }

    /// A logger that wrote a row twice: the refusal says so; a time repeated with other readings
    /// is only a time that does not increase.
    #[test]
    fn a_row_written_twice_is_named_as_such() {
        let e = err(
            b"time_s,T_a,E_z\n0,20,0\n15,21,\n15,21,\n30,22,1\n",
            NanPolicy::Interpolate,
        );
        assert!(
            e.contains("row 3, column `time_s`: time is not strictly increasing (15 after 15): the row repeats the one before it in every column"),
            "{e}"
        );
        let e = err(
            b"time_s,T_a,E_z\n0,20,0\n15,21,0\n15,22,0\n",
            NanPolicy::Error,
        );
        assert!(e.contains("(15 after 15)") && !e.contains("repeats"), "{e}");
    }

    /// A local clock that leaves daylight saving time repeats an hour: the refusal says so and
    /// how to write the times; a step back of another size does not.
    #[test]
    fn a_clock_set_back_an_hour_is_named_as_such() {
        let e = err(
            b"time,T_a,E_z\n2026-10-25T02:59:30,20,0\n2026-10-25T02:59:45,21,0\n2026-10-25T02:00:00,22,0\n",
            NanPolicy::Error,
        );
        assert!(
            e.contains("row 3, column `time`: time is not strictly increasing (-3585 s after the row before): an hour back (a local clock leaving daylight saving time?"),
            "{e}"
        );
        let e = err(
            b"time,T_a,E_z\n2026-10-25T02:59:30,20,0\n2026-10-25T02:59:45,21,0\n2026-10-25T02:30:00,22,0\n",
            NanPolicy::Error,
        );
        assert!(!e.contains("an hour back"), "{e}");
        // a clock of seconds has no daylight saving time
        let e = err(
            b"time_s,T_a,E_z\n3590,20,0\n3600,21,0\n15,22,0\n",
            NanPolicy::Error,
        );
        assert!(!e.contains("an hour back"), "{e}");
    }

    #[test]
    fn lines_are_the_files_own_with_crlf_ends_and_blank_lines() {
        // a Windows logger's CRLF, and a blank line before the bad cell: line 5 of the file
        for text in [
            &b"time_s,T_a,E_z\r\n0,20,0\r\n15,21,0\r\n\r\n30,,0\r\n"[..],
            &b"time_s,T_a,E_z\n0,20,0\n15,21,0\n\n30,,0\n"[..],
        ] {
            let e = err(text, NanPolicy::Error);
            assert!(e.contains(", line 5, row 3, column `T_a`"), "{e}");
        }
        // a row with too few fields, after CRLF ends
        let e = err(b"time_s,T_a,E_z\r\n0,20,0\r\n15,21\r\n", NanPolicy::Error);
        assert!(
            e.contains(", line 3, row 2") && e.contains("2 fields"),
            "{e}"
        );
    }

    #[test]
    fn refuses_values_too_large_to_compute_with() {
        let e = err(b"time_s,T_a,E_z\n0,20,0\n15,21,2e154\n", NanPolicy::Error);
        assert!(
            e.contains("row 2") && e.contains("E_z") && e.contains("2e154"),
            "{e}"
        );
        let e = err(b"time_s,T_a,E_z\n0,20,0\n1e300,21,1\n", NanPolicy::Error);
        assert!(e.contains("row 2") && e.contains("time_s"), "{e}");
        // epoch seconds are fine
        let p = write(b"time_s,T_a,E_z\n1790000000,20,0\n1790000015,21,1\n");
        assert!(Run::read_csv(&p.0, NanPolicy::Error).is_ok());
    }

    #[test]
    fn reads_a_good_file() {
        let p = write(b"time_s,T_a,E_z,U_rpm,note\n0,20,0,0,x\n150,21,1.5,3000,y\n");
        let r = Run::read_csv(&p.0, NanPolicy::Error).unwrap();
        assert_eq!(r.names, ["T_a", "E_z", "U_rpm"]);
        assert_eq!(r.ignored, ["note"]);
        assert_eq!(r.column("E_z").unwrap(), &[0.0, 1.5]);
        assert!(r.column("E_x").unwrap_err().to_string().contains("E_x"));
    }

    #[test]
    fn refusals_name_file_row_and_column() {
        let e = err(b"time_s,T_a\n0,20\n150,abc\n", NanPolicy::Error);
        assert!(
            e.contains("row 2") && e.contains("`T_a`") && e.contains("line 3"),
            "{e}"
        );
        let e = read_err(b"time_s;T_a\n0;20,5\n", b';');
        assert!(
            e.contains("row 1")
                && e.contains("\"20,5\" is not a number (a decimal comma? read the file with --decimal , (decimal=\",\" in Python), or write 20.5)"),
            "{e}"
        );
        let e = read_err(b"time_s;T_a\n0;1,2,3\n", b';');
        assert!(e.ends_with("\"1,2,3\" is not a number"), "{e}");
        // a logger's date-times under `time_s`: the fix is the column's name
        let e = err(b"time_s,T_a\n2024-03-01 08:00:00,20\n", NanPolicy::Error);
        assert!(
            e.contains("row 1") && e.contains("`time_s`") && e.contains("name the column `time`"),
            "{e}"
        );
        let e = err(b"time_s,T_a\nnoon,20\n", NanPolicy::Error);
        assert!(e.ends_with("\"noon\" is not a number"), "{e}");
        let e = err(b"time_s,T_a\n0,20\n0,21\n", NanPolicy::Error);
        assert!(
            e.contains("strictly increasing") && e.contains("row 2"),
            "{e}"
        );
        let e = err(b"t,T_a\n0,20\n", NanPolicy::Error);
        assert!(e.contains("no `time_s`"), "{e}");
        let e = err(b"time_s,T_a\n", NanPolicy::Error);
        assert!(e.contains("no data rows"), "{e}");
        let e = err(b"time_s,T_a\n0,\n", NanPolicy::Error);
        assert!(e.contains("missing value") && e.contains("row 1"), "{e}");
        let e = err(b"time_s,T_a\n0,\xff\n", NanPolicy::Error);
        assert!(e.contains("UTF-8"), "{e}");
        let e = err(b"time_s,T_a\n0,1,2\n", NanPolicy::Error);
        assert!(e.contains("3 fields"), "{e}");
    }

    #[test]
    fn reads_iso_date_times_as_seconds_since_the_first_row() {
        let p = write(
            b"time,T_a,E_z\n2025-03-04T23:59:45,20,0\n2025-03-05 00:00:00,21,1\n\
              2025-03-05T00:00:15.25,22,2\n",
        );
        let r = Run::read_csv(&p.0, NanPolicy::Error).unwrap();
        assert_eq!(r.time_s, [0.0, 15.0, 30.25]);
        assert_eq!(r.names, ["T_a", "E_z"]);
        assert!(r.ignored.is_empty());
        // with `time_s` beside it, `time_s` is the clock and `time` an ignored column
        let p = write(b"time,time_s,T_a\nmonday,0,20\ntuesday,15,21\n");
        let r = Run::read_csv(&p.0, NanPolicy::Error).unwrap();
        assert_eq!(
            (r.time_s.as_slice(), r.ignored.as_slice()),
            ([0.0, 15.0].as_slice(), ["time".to_string()].as_slice())
        );
        let e = err(
            b"time,T_a\n2025-03-04T08:00:00,20\n03/04/2025 08:00:15,21\n",
            NanPolicy::Error,
        );
        assert!(
            e.contains("row 2") && e.contains("`time`") && e.contains("ISO-8601"),
            "{e}"
        );
        let e = err(
            b"time,T_a\n2025-03-04T08:00:00,20\n2025-03-04T08:00:00,21\n",
            NanPolicy::Error,
        );
        assert!(
            e.contains("row 2") && e.contains("`time`") && e.contains("0 s after"),
            "{e}"
        );
        let e = err(b"time,T_a\n2025-03-04T08:00:00,20\n,21\n", NanPolicy::Drop);
        assert!(e.contains("row 2") && e.contains("time is missing"), "{e}");
        let e = err(b"T_a\n20\n", NanPolicy::Error);
        assert!(
            e.contains("no `time_s` column (seconds) or `time` column"),
            "{e}"
        );
    }

    #[test]
    fn nan_policies() {
        let text = b"time_s,T_a,E_z\n0,20,0\n10,NaN,1\n20,22,2\n30,23,\n";
        let p = write(text);
        let r = Run::read_csv(&p.0, NanPolicy::Drop).unwrap();
        assert_eq!(r.time_s, [0.0, 20.0]);
        assert_eq!(r.dropped_rows, [2, 4]);
        let r = Run::read_csv(&p.0, NanPolicy::Interpolate).unwrap();
        assert_eq!(r.column("T_a").unwrap(), &[20.0, 21.0, 22.0, 23.0]);
        assert_eq!(r.column("E_z").unwrap(), &[0.0, 1.0, 2.0, 2.0]);
        assert_eq!(r.interpolated, 2);
    }

    /// Found by the `csv_run` fuzz target: a gap between values of opposite sign near the f64
    /// limit was filled with -inf (their difference overflowed). A run now refuses such values
    /// before interpolating (`MAX_ABS_VALUE`), so the interpolation is checked on its own.
    #[test]
    fn interpolation_stays_finite_near_the_limits() {
        let fill = |t: &[f64], v: &[f64]| {
            let mut v = v.to_vec();
            interpolate_gaps(t, &mut v);
            v
        };
        assert_eq!(
            fill(&[0.0, 1.0, 2.0], &[1e308, f64::NAN, -1e308]),
            [1e308, 0.0, -1e308]
        );
        assert_eq!(
            fill(&[-1e308, 0.0, 1e308], &[0.0, f64::NAN, 4.0]),
            [0.0, 2.0, 4.0]
        );
        assert_eq!(
            fill(&[0.0, 1.0, 2.0], &[1.7e308, f64::NAN, 1.7e308]),
            [1.7e308; 3]
        );
        assert_eq!(
            fill(&[0.0, 5e-324, 1e-323], &[1.0, f64::NAN, 3.0]),
            [1.0, 2.0, 3.0]
        );
        // and a file with such values is refused where they are
        let e = err(
            b"time_s,T_a\n0,1e308\n1,\n2,-1e308\n",
            NanPolicy::Interpolate,
        );
        assert!(e.contains("row 1") && e.contains("T_a"), "{e}");
    }

    #[test]
    fn reads_other_delimiters_and_says_which_one_is_likely() {
        let text = b"time_s;T_a;E_z\n0;20;0\n15;21;1.5\n";
        let semi = Dialect::new(";", ".").unwrap();
        let r = Run::from_csv_reader_with(&text[..], "semi.csv", NanPolicy::Error, semi).unwrap();
        assert_eq!(r.column("E_z").unwrap(), &[0.0, 1.5]);
        let e = Run::from_csv_reader(&text[..], "semi.csv", NanPolicy::Error)
            .unwrap_err()
            .to_string();
        assert!(e.contains("semi.csv") && e.contains("';'"), "{e}");
    }

    /// A spreadsheet in a German or French locale: `;` between fields, a comma for the decimals.
    /// Read with its decimal mark, each number is the one written; without it, the refusal says
    /// how; with it, a point (a thousands separator, or a file of points after all) is refused,
    /// not read as a comma would be.
    #[test]
    fn reads_a_decimal_comma_when_asked_and_says_how_when_not() {
        let text = b"time_s;T_a;E_z\n0;20,5;-0,25\n15;21;1,5e1\n30;NaN;2\n";
        let comma = Dialect::new(";", ",").unwrap();
        let r =
            Run::from_csv_reader_with(&text[..], "de.csv", NanPolicy::Interpolate, comma).unwrap();
        assert_eq!(r.time_s, [0.0, 15.0, 30.0]);
        assert_eq!(r.column("T_a").unwrap(), &[20.5, 21.0, 21.0]);
        assert_eq!(r.column("E_z").unwrap(), &[-0.25, 15.0, 2.0]);
        let semi = Dialect::new(";", ".").unwrap();
        let e = Run::from_csv_reader_with(&text[..], "de.csv", NanPolicy::Error, semi)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("de.csv, line 2, row 1, column `T_a`: \"20,5\" is not a number (a decimal comma? read the file with --decimal ,"),
            "{e}"
        );
        for cell in ["1.020,5", "20.5", "1,2,3"] {
            let t = format!("time_s;T_a\n0;{cell}\n");
            let e = Run::from_csv_reader_with(t.as_bytes(), "de.csv", NanPolicy::Error, comma)
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("{cell:?} is not a number")), "{e}");
        }
        assert!(Dialect::new(",", ",").is_err());
        assert!(Dialect::new(";", "x").is_err());
        assert!(Dialect::new("\"", ".").is_err());
    }

    #[test]
    fn reads_from_any_reader() {
        let r = Run::from_csv_reader(&b"time_s,T_a\n0,1\n1,2\n"[..], "<bytes>", NanPolicy::Error)
            .unwrap();
        assert_eq!(r.source, "<bytes>");
        assert_eq!(r.column("T_a").unwrap(), &[1.0, 2.0]);
        let e = Run::from_csv_reader(&b"time_s,T_a\n0,x\n"[..], "<bytes>", NanPolicy::Error)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("<bytes>, line 2, row 1, column `T_a`"), "{e}");
    }

    /// A day of a machine warming and cooling, three temperatures and a probe quantised as a
    /// logger writes them (0.1 K, 0.1 µm), with noise from `seed`.
    fn logged(seed: u64, rows: usize) -> Vec<Vec<f64>> {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut noise = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.1
        };
        let q = |v: f64| (v * 10.0).round() / 10.0;
        let mut cols = vec![Vec::new(); 4];
        for r in 0..rows {
            let t = r as f64 / rows as f64 * std::f64::consts::PI;
            let warm = t.sin();
            cols[0].push(q(20.0 + 6.0 * warm + noise()));
            cols[1].push(q(20.0 + 3.0 * warm + noise()));
            cols[2].push(q(20.0 + 0.5 * warm + noise()));
            cols[3].push(q(25.0 * warm + noise()));
        }
        cols
    }

    fn view(cols: &[Vec<f64>], rows: std::ops::Range<usize>) -> Vec<&[f64]> {
        cols.iter().map(|c| &c[rows.clone()]).collect()
    }

    fn lg<'a>(source: &'a str, time: &'a [f64], cols: &'a [&'a [f64]]) -> Logged<'a> {
        Logged { source, time, cols }
    }

    /// A 15-s clock over `rows`.
    fn clock(rows: std::ops::Range<usize>) -> Vec<f64> {
        rows.map(|r| r as f64 * 15.0).collect()
    }

    #[test]
    fn rows_taken_from_the_training_log_in_turn_are_refused() {
        let run = logged(1, 2000);
        let t = clock(0..2000);
        let pick = |rows: &[usize]| -> (Vec<f64>, Vec<Vec<f64>>) {
            (
                rows.iter().map(|&r| t[r]).collect(),
                run.iter()
                    .map(|c| rows.iter().map(|&r| c[r]).collect())
                    .collect(),
            )
        };
        let even: Vec<usize> = (0..2000).step_by(2).collect();
        let odd: Vec<usize> = (1..2000).step_by(2).collect();
        let ((te, e), (to, o)) = (pick(&even), pick(&odd));
        let (ev, ov) = (view(&e, 0..1000), view(&o, 0..1000));
        let err = check_unseen(lg("even.csv", &te, &ev), lg("odd.csv", &to, &ov))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("odd.csv: ")
                && err.contains("of its 1000 rows (rows 1-998) fall between rows 1-999 of even.csv on its clock"),
            "{err}"
        );
        // every third row held out; a thinned copy of the training rows themselves
        let (two, third): (Vec<usize>, Vec<usize>) = (0..2000).partition(|r| r % 3 != 2);
        let ((tt, tw), (th, tr)) = (pick(&two), pick(&third));
        let (tv, hv) = (view(&tw, 0..tt.len()), view(&tr, 0..th.len()));
        assert!(check_unseen(lg("two.csv", &tt, &tv), lg("third.csv", &th, &hv)).is_err());
        let all = view(&run, 0..2000);
        assert!(check_unseen(lg("run.csv", &t, &all), lg("thin.csv", &te, &ev)).is_err());
        // the clock restarted at 0: each odd row now on the stamp of the even row before it,
        // which it reads as within a step, so refused too; restarted anywhere else, the rows
        // meet others of the training run and are not recognised
        let restarted: Vec<f64> = to.iter().map(|x| x - to[0]).collect();
        assert!(check_unseen(lg("even.csv", &te, &ev), lg("odd.csv", &restarted, &ov)).is_err());
        let later: Vec<f64> = to.iter().map(|x| x + 9000.0).collect();
        assert!(check_unseen(lg("even.csv", &te, &ev), lg("odd.csv", &later, &ov)).is_ok());
    }

    #[test]
    fn a_held_out_piece_of_the_training_run_is_refused() {
        let run = logged(1, 2000);
        let train = view(&run, 0..2000);
        let e = check_unseen(
            lg("run.csv", &clock(0..2000), &train),
            lg("tail.csv", &clock(0..500), &view(&run, 1500..2000)),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("tail.csv: rows 1-500 are rows 1501-2000 of run.csv ("),
            "{e}"
        );
        assert!(e.contains("which the fit trains on"), "{e}");
        // a piece that only begins inside the training rows
        let mut more = logged(3, 2400);
        for (m, r) in more.iter_mut().zip(&run) {
            m[..100].copy_from_slice(&r[1900..]);
        }
        let e = check_unseen(
            lg("run.csv", &clock(0..2000), &train),
            lg("next.csv", &clock(0..500), &view(&more, 0..500)),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("next.csv: rows 1-100 are rows 1901-2000 of run.csv"),
            "{e}"
        );
    }

    #[test]
    fn another_run_of_the_same_machine_is_not_refused() {
        // the same duty, other noise: the states repeat, quantised to the logger's resolution,
        // but not ten changing rows at one offset
        let (a, b) = (logged(1, 2000), logged(2, 2000));
        let run = view(&a, 0..2000);
        assert!(check_shared(
            lg("run.csv", &[], &run),
            lg("other.csv", &[], &view(&b, 0..2000))
        )
        .is_ok());
        // an idle machine: every row alike in both
        let idle: Vec<Vec<f64>> = (0..4).map(|c| vec![20.0 + c as f64; 500]).collect();
        let still = view(&idle, 0..500);
        let t = clock(0..500);
        assert!(check_unseen(lg("idle.csv", &t, &still), lg("idle2.csv", &t, &still)).is_ok());
        // fewer changing rows than the floor, or other columns: nothing to say
        assert!(check_unseen(
            lg("run.csv", &clock(0..2000), &run),
            lg(
                "short.csv",
                &clock(0..SHARED_ROWS_MIN - 1),
                &view(&a, 0..SHARED_ROWS_MIN - 1)
            )
        )
        .is_ok());
        let few = &view(&a, 0..2000)[..3];
        assert!(check_unseen(
            lg("run.csv", &clock(0..2000), &run),
            lg("few.csv", &clock(0..2000), few)
        )
        .is_ok());
    }

    #[test]
    fn another_run_on_the_same_clock_is_not_refused() {
        // the same duty on the same clock (a logger's time of day), on the stamps and between
        // them: its temperatures within the logger's resolution of the training run's, as
        // `logged` makes them, but its probe's drift 5 % larger (no machine repeats its drift
        // to a tenth of a µm: on the real 46-h run no row of one quarter read within three
        // steps of another quarter's on one clock, where 98 % of odd rows did of even ones)
        let a = logged(1, 2000);
        let mut b = logged(2, 2000);
        for v in b[3].iter_mut() {
            *v = (*v * 1.05 * 10.0).round() / 10.0;
        }
        let t = clock(0..2000);
        let shifted: Vec<f64> = t.iter().map(|x| x + 7.5).collect();
        for other in [&t, &shifted] {
            assert!(check_unseen(
                lg("run.csv", &t, &view(&a, 0..2000)),
                lg("other.csv", other, &view(&b, 0..2000))
            )
            .is_ok());
        }
        // with the very drift, the runs are one log's rows to this check: refused
        let b2 = logged(2, 2000);
        assert!(check_unseen(
            lg("run.csv", &t, &view(&a, 0..2000)),
            lg("other.csv", &shifted, &view(&b2, 0..2000))
        )
        .is_err());
    }

    #[test]
    fn a_loggers_header_is_read_through_its_renames() {
        let text = "Time (s),Temp t1 (°C),Disp ch1 (um)\n0,20.0,0.0\n15,20.5,1.5\n";
        let renames = [
            Rename::parse("Time (s)=time_s").unwrap(),
            Rename::parse("Temp * (°C)=T_*").unwrap(),
            Rename::parse("Disp * (um)=E_*").unwrap(),
        ];
        let r = Run::from_csv_reader_renamed(
            text.as_bytes(),
            "log.csv",
            NanPolicy::Error,
            Dialect::default(),
            &renames,
        )
        .unwrap();
        assert_eq!(r.names, ["T_t1", "E_ch1"]);
        assert_eq!(r.column("E_ch1").unwrap(), &[0.0, 1.5]);
        // without them: no time column, and with the time alone no data column; each says how
        let e = Run::from_csv_reader(text.as_bytes(), "log.csv", NanPolicy::Error)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("log.csv: no `time_s` column") && e.contains("--rename 'OLD=NEW'"),
            "{e}"
        );
        let e = Run::from_csv_reader_renamed(
            text.as_bytes(),
            "log.csv",
            NanPolicy::Error,
            Dialect::default(),
            &renames[..1],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("log.csv: no column named as data: temperatures `T_*`, errors `E_*`, inputs `U_*` (columns are: time_s, Temp t1 (°C), Disp ch1 (um)); map"),
            "{e}"
        );
    }
}
