//! How a run's CSV text is written: its field delimiter and its decimal mark, and the reading of
//! one cell under them. The one owner of these rules for every reader of runs: the library's
//! CSV reader (`run`, with the `fit` feature) and the edge's line filter (predict-only), so a
//! file the library reads is read the same way beside the machine.

use crate::error::{Error, Result};
use crate::timeaxis::IsoClock;

/// How a run's CSV is written: its field delimiter and its decimal mark. A spreadsheet saved in a
/// German or French locale writes `20,5` for 20.5 and separates fields by `;`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dialect {
    pub delimiter: u8,
    /// `b'.'` or `b','`.
    pub decimal: u8,
}

impl Default for Dialect {
    fn default() -> Self {
        Dialect {
            delimiter: b',',
            decimal: b'.',
        }
    }
}

/// The delimiters a user may give by name (a tab is hard to type on a command line).
const NAMED_DELIMITERS: [(&str, &str); 4] = [
    ("tab", "\t"),
    ("\\t", "\t"),
    ("comma", ","),
    ("semicolon", ";"),
];

impl Dialect {
    /// A delimiter as a user writes it: one character, or `tab` (`\t`), `comma`, `semicolon`.
    pub fn delimiter_named(text: &str) -> &str {
        NAMED_DELIMITERS
            .iter()
            .find(|(name, _)| *name == text)
            .map_or(text, |(_, d)| d)
    }

    /// The dialect named by a delimiter (one ASCII character, not a quote or a line end, or one
    /// of the names of [`Dialect::delimiter_named`]) and a decimal mark (`.` or `,`, not the
    /// delimiter): the one check behind every reader's options.
    pub fn new(delimiter: &str, decimal: &str) -> Result<Dialect> {
        let delimiter = match Dialect::delimiter_named(delimiter).as_bytes() {
            [b] if b.is_ascii() && !matches!(b, b'"' | b'\n' | b'\r') => *b,
            _ => {
                return Err(Error::param(
                    "delimiter",
                    format!(
                        "must be one ASCII character (not a quote or newline) or tab, comma, \
                         semicolon; got {delimiter:?}"
                    ),
                ))
            }
        };
        let decimal = match decimal {
            "." => b'.',
            "," => b',',
            _ => {
                return Err(Error::param(
                    "decimal",
                    format!("must be \".\" or \",\", got {decimal:?}"),
                ))
            }
        };
        if decimal == delimiter {
            return Err(Error::param(
                "decimal",
                "a decimal comma needs another field delimiter (\";\" as a spreadsheet in that locale writes, or tab)",
            ));
        }
        Ok(Dialect { delimiter, decimal })
    }

    /// A cell's number: empty or `NaN` is NaN (a missing value), anything else must be a finite
    /// number written with this decimal mark. With a comma, one comma is the decimal mark and a
    /// point is refused (a thousands separator, or a file that writes points after all: neither
    /// is read as the other). `None`: not a number (say why with [`Dialect::not_a_number`]).
    pub fn number(&self, cell: &str) -> Option<f64> {
        if self.decimal != b',' {
            return parse_cell(cell);
        }
        if cell.contains('.') {
            return None;
        }
        match cell.matches(',').count() {
            0 => parse_cell(cell),
            1 => parse_cell(&cell.replacen(',', ".", 1)),
            _ => None,
        }
    }

    /// Whether a cell that is not a number here is one written with the other decimal mark
    /// (`20,5` in a file of decimal points, `20.5` under a decimal comma): a file read with the
    /// wrong `--decimal`, not a faulty reading.
    pub fn other_mark(&self, cell: &str) -> bool {
        // `number` reads no delimiter: only the mark changes
        let other = Dialect {
            decimal: if self.decimal == b',' { b'.' } else { b',' },
            ..*self
        };
        self.number(cell).is_none() && other.number(cell).is_some_and(f64::is_finite)
    }

    /// [`not_a_number`] in a file of this dialect: with a decimal comma, a point in the cell is
    /// named as what it is.
    pub fn not_a_number(&self, column: &str, cell: &str) -> String {
        if self.decimal == b',' && cell.contains('.') {
            format!(
                "{cell:?} is not a number with a decimal comma (a point in it: the file writes \
                 decimal points, or thousands separators; read it without --decimal , or write \
                 the number without them)"
            )
        } else {
            not_a_number(column, cell)
        }
    }

    /// A header read as one column whose name holds another common delimiter: the words that
    /// say so (before "no such column" would), or `None`.
    pub fn one_column_header(&self, names: &[&str]) -> Option<String> {
        let [only] = names else { return None };
        [b',', b';', b'\t', b'|']
            .into_iter()
            .find(|&d| d != self.delimiter && only.as_bytes().contains(&d))
            .map(|d| {
                format!(
                    "the header is one column, {only:?}: are the fields separated by {:?}? \
                     (delimiter: {:?})",
                    d as char, self.delimiter as char
                )
            })
    }

    /// The fields of one line of text, as a CSV reader gives them: split at the delimiter
    /// outside double quotes (a spreadsheet quotes a name holding the delimiter), each
    /// [`unquoted`]. The library's reader (the `csv` crate) does this itself; the edge's
    /// line filter reads its lines with this. An escaped quote inside a quoted field (`""`) is
    /// left as written (a run's fields are names, numbers and times).
    pub fn fields<'l>(&self, line: &'l str) -> Vec<&'l str> {
        let mut out = Vec::new();
        let (mut start, mut quoted) = (0, false);
        for (i, b) in line.bytes().enumerate() {
            if b == b'"' {
                quoted = !quoted;
            } else if b == self.delimiter && !quoted {
                out.push(unquoted(&line[start..i]));
                start = i + 1;
            }
        }
        out.push(unquoted(&line[start..]));
        out
    }
}

/// A field split from a line by hand, as a CSV reader gives it: trimmed, and without the pair of
/// double quotes around it (`"T_a"`, `"20.5"`: a spreadsheet or logger that quotes every field,
/// or its header).
pub fn unquoted(field: &str) -> &str {
    let f = field.trim();
    match f.strip_prefix('"').and_then(|g| g.strip_suffix('"')) {
        Some(inner) => inner.trim(),
        None => f,
    }
}

/// The refusal of a cell of `column` that is not a number, with the likely fix: for a decimal
/// comma (a spreadsheet saved in a German or French locale writes `20,5` for 20.5), and for a
/// logger's date-times in `time_s` (the column to name `time`). The CSV reader's, the edge's and
/// `Run.from_frame`'s words.
pub fn not_a_number(column: &str, cell: &str) -> String {
    if column == "time_s" && IsoClock::new().seconds(cell).is_ok() {
        return format!(
            "{cell:?} is not a number of seconds (a date-time: name the column `time` and it is \
             read as ISO-8601, the run's clock starting at its first row)"
        );
    }
    let dotted = cell.trim().replacen(',', ".", 1);
    match parse_cell(&dotted) {
        Some(_) if cell.matches(',').count() == 1 => {
            format!(
                "{cell:?} is not a number (a decimal comma? read the file with --decimal , \
                 (decimal=\",\" in Python), or write {dotted})"
            )
        }
        _ => format!("{cell:?} is not a number"),
    }
}

fn parse_cell(cell: &str) -> Option<f64> {
    if cell.is_empty() || cell.eq_ignore_ascii_case("nan") {
        return Some(f64::NAN);
    }
    cell.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// One header name mapped to the run format's (`--rename 'Temp * (°C)=T_*'`): a logger names its
/// columns its own way (`Time (s)`, `Temp t1 (°C)`, `Disp ch1 (um)`), the run format by prefix
/// (`time_s`, `T_`, `E_`, `U_`). `from` is a column's name, or a pattern with one `*` standing for
/// any non-empty text; `to` is the new name, a `*` in it replaced by that text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rename {
    from: String,
    to: String,
}

impl Rename {
    /// `OLD=NEW` as a user writes it (split at the last `=`; each side trimmed, neither empty, at
    /// most one `*` on each, and a `*` in NEW only with one in OLD).
    pub fn parse(text: &str) -> Result<Rename> {
        let bad = |why: &str| {
            Error::param(
                "rename",
                format!(
                    "{text:?}: {why} (write OLD=NEW, e.g. 'Time (s)=time_s' or 'Temp * (°C)=T_*')"
                ),
            )
        };
        let (from, to) = text.rsplit_once('=').ok_or_else(|| bad("no `=`"))?;
        let (from, to) = (from.trim(), to.trim());
        if from.is_empty() || to.is_empty() {
            return Err(bad("a name on each side of `=`"));
        }
        if from.matches('*').count() > 1 || to.matches('*').count() > 1 {
            return Err(bad("one `*` at most on each side"));
        }
        if to.contains('*') && !from.contains('*') {
            return Err(bad(
                "a `*` in the new name stands for what the old name's `*` matched",
            ));
        }
        Ok(Rename {
            from: from.to_string(),
            to: to.to_string(),
        })
    }

    /// The new name of column `name`, when this rename matches it.
    fn apply(&self, name: &str) -> Option<String> {
        let Some((head, tail)) = self.from.split_once('*') else {
            return (name == self.from).then(|| self.to.clone());
        };
        let middle = name
            .strip_prefix(head)?
            .strip_suffix(tail)
            .filter(|m| !m.is_empty())?;
        Some(self.to.replacen('*', middle, 1))
    }
}

/// Renames header `names` of `source` in place: each column by the first of `renames` that
/// matches it, the others as they are. A rename that matches no column is refused (a misspelt
/// name would leave the column ignored and the run read without it), naming the file and its
/// columns.
pub fn rename_columns(source: &str, names: &mut [String], renames: &[Rename]) -> Result<()> {
    let original = names.join(", ");
    let mut used = vec![false; renames.len()];
    for name in names.iter_mut() {
        if let Some((k, new)) = renames
            .iter()
            .enumerate()
            .find_map(|(k, r)| r.apply(name).map(|n| (k, n)))
        {
            used[k] = true;
            *name = new;
        }
    }
    match used.iter().position(|u| !u) {
        None => Ok(()),
        Some(k) => Err(Error::Parse {
            file: source.to_string(),
            line: Some(1),
            row: None,
            column: None,
            reason: format!(
                "--rename '{}={}' matches no column of the header (columns are: {original})",
                renames[k].from, renames[k].to,
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_delimiters_and_their_checks() {
        assert_eq!(Dialect::new("tab", ",").unwrap().delimiter, b'\t');
        assert_eq!(Dialect::new("\\t", ".").unwrap().delimiter, b'\t');
        assert_eq!(Dialect::new("semicolon", ",").unwrap().delimiter, b';');
        assert_eq!(Dialect::new("comma", ".").unwrap(), Dialect::default());
        assert!(Dialect::new("comma", ",").is_err());
        assert!(Dialect::new(";;", ".").is_err());
        assert!(Dialect::new("\"", ".").is_err());
        assert!(Dialect::new(";", "'").is_err());
    }

    #[test]
    fn a_cell_under_each_decimal_mark() {
        let dot = Dialect::default();
        let comma = Dialect::new(";", ",").unwrap();
        assert_eq!(dot.number("20.5"), Some(20.5));
        assert_eq!(comma.number("20,5"), Some(20.5));
        assert_eq!(comma.number("-3"), Some(-3.0));
        assert!(dot.number("").unwrap().is_nan());
        assert!(comma.number("NaN").unwrap().is_nan());
        assert_eq!(dot.number("20,5"), None);
        assert_eq!(comma.number("20.5"), None);
        assert_eq!(comma.number("1.020,5"), None);
        assert_eq!(comma.number("1,0,2"), None);
        assert_eq!(dot.number("inf"), None);
        assert!(dot.not_a_number("T_a", "20,5").contains("--decimal ,"));
        assert!(comma.not_a_number("T_a", "20.5").contains("a point in it"));
        assert!(dot.other_mark("20,5") && comma.other_mark("20.5"));
        assert!(!dot.other_mark("20.5") && !dot.other_mark("oops") && !dot.other_mark(""));
        assert!(!comma.other_mark("1.020,5") && !comma.other_mark("20,5"));
    }

    #[test]
    fn a_quoted_field_is_read_without_its_quotes() {
        assert_eq!(unquoted(" \"T_a\" "), "T_a");
        assert_eq!(unquoted("\"20.5\""), "20.5");
        assert_eq!(unquoted("20.5"), "20.5");
        assert_eq!(unquoted("\""), "\"");
        assert_eq!(unquoted("\"\""), "");
    }

    #[test]
    fn a_line_splits_at_the_delimiter_outside_quotes() {
        let comma = Dialect::default();
        assert_eq!(
            comma.fields("\"0\",\"T_a, front\", \"T_b\" ,7"),
            ["0", "T_a, front", "T_b", "7"]
        );
        let semi = Dialect::new(";", ",").unwrap();
        assert_eq!(semi.fields("a;\"b;c\";;d"), ["a", "b;c", "", "d"]);
        assert_eq!(semi.fields(""), [""]);
        // an escaped quote keeps its field whole; an unclosed quote runs to the line's end
        assert_eq!(semi.fields("\"x\"\"y\";z"), ["x\"\"y", "z"]);
        assert_eq!(semi.fields("\"x;y"), ["\"x;y"]);
    }

    #[test]
    fn a_header_of_one_column_holding_another_delimiter_is_named() {
        let d = Dialect::default();
        let e = d.one_column_header(&["time_s;T_a;E_x"]).unwrap();
        assert!(e.contains("separated by ';'"), "{e}");
        assert_eq!(d.one_column_header(&["time_s", "T_a"]), None);
        assert_eq!(d.one_column_header(&["time_s"]), None);
    }

    #[test]
    fn a_loggers_names_are_mapped_to_the_run_format() {
        let r = |t: &str| Rename::parse(t).unwrap();
        let renames = [
            r("Time (s)=time_s"),
            r(" Temp * (°C) = T_* "),
            r("Disp *=E_*"),
        ];
        let mut names: Vec<String> = [
            "Time (s)",
            "Temp t1 (°C)",
            "Temp  (°C)",
            "Disp ch1 (um)",
            "Note",
        ]
        .map(String::from)
        .to_vec();
        rename_columns("log.csv", &mut names, &renames).unwrap();
        // `*` stands for non-empty text; an unmatched column keeps its name
        assert_eq!(
            names,
            ["time_s", "T_t1", "Temp  (°C)", "E_ch1 (um)", "Note"]
        );
        // the first rename that matches wins
        let mut names = vec!["Temp t1 (°C)".to_string()];
        rename_columns(
            "log.csv",
            &mut names,
            &[r("Temp t1 (°C)=T_ambient"), r("Temp *=T_*")],
        )
        .unwrap_err(); // the second matches nothing now: refused
        let mut names = vec!["Temp t1 (°C)".to_string(), "Temp t2 (°C)".to_string()];
        rename_columns(
            "log.csv",
            &mut names,
            &[r("Temp t1 (°C)=T_ambient"), r("Temp * (°C)=T_*")],
        )
        .unwrap();
        assert_eq!(names, ["T_ambient", "T_t2"]);
        // a rename that matches no column names the file and the columns as written
        let mut names = vec!["Zeit".to_string(), "T_a".to_string()];
        let e = rename_columns("log.csv", &mut names, &[r("Time=time_s")])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "log.csv, line 1: --rename 'Time=time_s' matches no column of the header (columns are: Zeit, T_a)"
        );
        for bad in ["Time", "=time_s", "Time=", "a*b*=c", "Time=T_*"] {
            let e = Rename::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("rename") && e.contains(&format!("{bad:?}")),
                "{e}"
            );
        }
    }
}
