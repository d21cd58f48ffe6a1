//! The streaming command-line filter's line parser: a CSV header picks the model's feature
//! columns by name, then each data line becomes one sample. The CLI (`main.rs`) and the fuzz
//! target `edge_stream` run lines through this one code path. Fields are split at the
//! [`Dialect`]'s delimiter and numbers read under its decimal mark, by the core's rules (the
//! library's CSV reader reads the same file the same way); a field in double quotes is read
//! without them, and a delimiter inside the quotes does not split it.

use thermerr_core::dialect::{rename_columns, Dialect, Rename};
use thermerr_core::guard::GuardedPredictor;
use thermerr_core::timeaxis::{time_column, IsoClock, TimeKind, TIME_S};

use crate::Predictor;

/// A line's time field as written, and its seconds.
pub type Stamp<'l> = (&'l str, f64);

/// Where the model's features and the time are in the lines of one input.
#[derive(Clone, Debug)]
pub struct LineFilter {
    features: Vec<usize>,
    names: Vec<String>,
    /// the time column and how it is written (`time_s` seconds, or `time` ISO-8601 date-times)
    time: Option<(usize, TimeKind)>,
    clock: IsoClock,
    dialect: Dialect,
    width: usize,
    x: Vec<f64>,
    row: usize,
}

/// One prediction written by the filter: the line's time field as written (or, without a time
/// column, the count of rows predicted before it), that time in seconds (since the epoch for a
/// `time` column of date-times) and the predicted error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output<'l> {
    pub time: Option<&'l str>,
    pub t_s: Option<f64>,
    pub row: usize,
    pub y: f64,
}

/// A guarded line's outcome: a prediction (the predictor's `write_status` says how it was
/// made), or nothing yet because the named sensor has not given a good reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guarded<'l> {
    Predicted(Output<'l>),
    Waiting,
}

impl LineFilter {
    /// Reads the header line of a CSV with `,` between fields and decimal points: every feature
    /// the model reads must be a column of it.
    pub fn new(header: &str, p: &Predictor) -> Result<Self, String> {
        LineFilter::with_dialect(header, p, Dialect::default())
    }

    /// [`LineFilter::new`] for lines written in `dialect` (another delimiter, a decimal comma).
    pub fn with_dialect(header: &str, p: &Predictor, dialect: Dialect) -> Result<Self, String> {
        LineFilter::with_renames(header, p, dialect, &[])
    }

    /// [`LineFilter::with_dialect`], the header's names mapped by `renames` first
    /// (`thermerr_core::dialect::rename_columns`, as the library's reader does; a rename that
    /// matches no column: `line 1: --rename ... matches no column ...`).
    pub fn with_renames(
        header: &str,
        p: &Predictor,
        dialect: Dialect,
        renames: &[Rename],
    ) -> Result<Self, String> {
        let fields: Vec<&str> = dialect.fields(
            header
                .trim_start_matches('\u{feff}')
                .trim_end_matches(['\r', '\n']),
        );
        if let Some(e) = dialect.one_column_header(&fields) {
            return Err(e);
        }
        let mut owned: Vec<String> = fields.iter().map(|f| f.to_string()).collect();
        rename_columns("", &mut owned, renames).map_err(|e| match e {
            thermerr_core::Error::Parse { reason, .. } => format!("line 1: {reason}"),
            e => e.to_string(),
        })?;
        let names: Vec<&str> = owned.iter().map(String::as_str).collect();
        let wanted = p
            .features()
            .ok_or("the model does not record its feature columns (fit it on a run)")?;
        let mut missing = Vec::new();
        let mut features = Vec::with_capacity(wanted.len());
        for w in wanted {
            match names.iter().position(|n| n == w) {
                Some(k) => features.push(k),
                None => missing.push(w.as_str()),
            }
        }
        if !missing.is_empty() {
            return Err(format!(
                "the input has no column {} (columns are: {}; a logger's own names are mapped \
                 with --rename 'OLD=NEW', e.g. --rename 'Temp * (°C)=T_*')",
                missing.join(", "),
                names.join(", ")
            ));
        }
        Ok(LineFilter {
            features,
            names: wanted.to_vec(),
            time: time_column(&names),
            clock: IsoClock::new(),
            dialect,
            width: names.len(),
            x: vec![0.0; p.n_inputs()],
            row: 0,
        })
    }

    /// The name of the time column the output echoes: the input's `time_s` or `time`, or
    /// `time_s` (then holding the row count) when the input has neither.
    pub fn time_name(&self) -> &'static str {
        self.time.map_or(TIME_S, |(_, k)| k.name())
    }

    /// Parses the model's features of one data line; returns them and the time field as written
    /// with its seconds.
    pub fn parse_row<'l>(&mut self, line: &'l str) -> Result<(&[f64], Option<Stamp<'l>>), String> {
        self.parse_fields(line, false)
    }

    /// As [`LineFilter::parse_row`]; with `missing_ok` a feature field that is not a finite
    /// number reads as NaN (a sensor fault for the guard) instead of rejecting the line, unless
    /// it is a number in the other decimal mark (the stream read with the wrong `--decimal`).
    /// The time field, when there is one, must be a finite number either way.
    fn parse_fields<'l>(
        &mut self,
        line: &'l str,
        missing_ok: bool,
    ) -> Result<(&[f64], Option<Stamp<'l>>), String> {
        let f = self.dialect.fields(line);
        if f.len() != self.width {
            return Err(format!("expected {} fields, got {}", self.width, f.len()));
        }
        let time = match self.time {
            None => None,
            Some((k, TimeKind::Seconds)) => {
                let t = f[k];
                match self.dialect.number(t) {
                    Some(v) if v.is_finite() => Some((t, v)),
                    Some(_) => return Err("column `time_s`: time is missing".into()),
                    None => {
                        let why = self.dialect.not_a_number(TIME_S, t);
                        return Err(format!("column `time_s`: {why}"));
                    }
                }
            }
            Some((k, TimeKind::Iso)) => {
                let t = f[k];
                match self.clock.seconds(t) {
                    Ok(v) if v.is_finite() => Some((t, v)),
                    Ok(_) => return Err("column `time`: time is missing".into()),
                    Err(e) => return Err(format!("column `time`: {e}")),
                }
            }
        };
        for ((xv, &k), name) in self.x.iter_mut().zip(&self.features).zip(&self.names) {
            let raw = f[k];
            match self.dialect.number(raw) {
                Some(v) if v.is_finite() => *xv = v,
                // a cell in the other decimal mark is the file read the wrong way, not a fault
                _ if missing_ok && !self.dialect.other_mark(raw) => *xv = f64::NAN,
                Some(_) => return Err(format!("column `{name}`: missing value ({raw:?})")),
                None => {
                    let why = self.dialect.not_a_number(name, raw);
                    return Err(format!("column `{name}`: {why}"));
                }
            }
        }
        Ok((&self.x, time))
    }

    /// One data line through a guarded model: a feature field that is empty or not a finite
    /// number is a sensor fault the guard handles, not a rejected line; a line of the wrong
    /// width or a bad time still is.
    pub fn feed_guarded<'l>(
        &mut self,
        g: &mut GuardedPredictor,
        line: &'l str,
    ) -> Result<Option<Guarded<'l>>, String> {
        let l = line.trim_end_matches(['\r', '\n']);
        if l.trim().is_empty() {
            return Ok(None);
        }
        let (x, time) = self.parse_fields(l, true)?;
        let (time, t_s) = (time.map(|t| t.0), time.map(|t| t.1));
        match g.step(t_s, x).map_err(|e| e.to_string())? {
            None => Ok(Some(Guarded::Waiting)),
            Some(y) => {
                let row = self.row;
                self.row += 1;
                Ok(Some(Guarded::Predicted(Output { time, t_s, row, y })))
            }
        }
    }

    /// One data line through the model: `Ok(None)` for a blank line, the prediction for a good
    /// one, the reason for a bad one (the caller reports it with the line number and goes on).
    pub fn feed<'l>(
        &mut self,
        p: &mut Predictor,
        line: &'l str,
    ) -> Result<Option<Output<'l>>, String> {
        let l = line.trim_end_matches(['\r', '\n']);
        if l.trim().is_empty() {
            return Ok(None);
        }
        let (x, time) = self.parse_row(l)?;
        let (time, t_s) = (time.map(|t| t.0), time.map(|t| t.1));
        let y = p.predict_sample_at(t_s, x).map_err(|e| e.to_string())?;
        let row = self.row;
        self.row += 1;
        Ok(Some(Output { time, t_s, row, y }))
    }
}
