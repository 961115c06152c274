//! Reading result CSVs back (`plot`, `animate --from`): RFC 4180 through the `csv` crate, so names
//! with commas, quotes or line breaks read as they were written.

use std::io::Read;

/// A result CSV that cannot be read as asked. `Display` is one line naming the file, the line and
/// the column at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {}", crate::scene::one_line(file), line.map(|l| format!(":{l}")).unwrap_or_default(), crate::scene::one_line(message))]
pub struct ResultCsvError {
    /// The file (or origin) name.
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<u64>,
    /// What is wrong.
    pub message: String,
}

/// Columns read from a result CSV: the times and, row after row, the requested columns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ResultTable {
    /// Column `t`, increasing.
    pub times: Vec<f64>,
    /// The requested columns, `names.len()` numbers per row.
    pub values: Vec<f64>,
}

/// Reads column `t` and the columns `names` of a result CSV. Errors (one line, naming `origin`
/// and the line): a missing column (the header is line 1), a malformed row, a field that is not a
/// finite number, times that do not increase.
pub fn read_columns(reader: impl Read, origin: &str, names: &[String]) -> Result<ResultTable, ResultCsvError> {
    let err = |line: Option<u64>, message: String| ResultCsvError {
        file: origin.to_string(),
        line,
        message,
    };
    let mut rdr = csv::ReaderBuilder::new().has_headers(true).from_reader(reader);
    let header = rdr
        .headers()
        .map_err(|e| err(Some(1), format!("not a result CSV: {}", cause(&e))))?
        .clone();
    let column = |name: &str| -> Result<usize, ResultCsvError> {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| err(Some(1), no_column(name, &header.iter().collect::<Vec<_>>())))
    };
    let t_col = column("t")?;
    let cols = names.iter().map(|n| column(n)).collect::<Result<Vec<_>, _>>()?;
    let mut table = ResultTable::default();
    let mut record = csv::StringRecord::new();
    loop {
        match rdr.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e.position().map(|p| p.line());
                return Err(err(line, format!("malformed CSV: {}", cause(&e))));
            }
        }
        let line = record.position().map(|p| p.line());
        let number = |k: usize| -> Result<f64, ResultCsvError> {
            let field = record.get(k).unwrap_or("");
            match field.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(err(
                    line,
                    format!("column '{}' is not a finite number: '{field}'", &header[k]),
                )),
            }
        };
        let t = number(t_col)?;
        if let Some(&last) = table.times.last() {
            if t <= last {
                return Err(err(
                    line,
                    format!(
                        "times must increase: t = {} after {}",
                        crate::output::shortest(t),
                        crate::output::shortest(last)
                    ),
                ));
            }
        }
        table.times.push(t);
        for &k in &cols {
            table.values.push(number(k)?);
        }
    }
    Ok(table)
}

/// The header (line 1) of a result CSV, as written: names with commas, quotes or line breaks
/// whole.
pub fn read_header(reader: impl Read, origin: &str) -> Result<Vec<String>, ResultCsvError> {
    let mut rdr = csv::ReaderBuilder::new().has_headers(true).from_reader(reader);
    let header = rdr.headers().map_err(|e| ResultCsvError {
        file: origin.to_string(),
        line: Some(1),
        message: format!("not a result CSV: {}", cause(&e)),
    })?;
    Ok(header.iter().map(str::to_string).collect())
}

/// `no column 'NAME' (its columns: …)`, at most 40 of them listed, with the nearest as a hint.
pub fn no_column(name: &str, header: &[&str]) -> String {
    const SHOWN: usize = 40;
    let mut list = header.iter().take(SHOWN).copied().collect::<Vec<_>>().join(", ");
    if header.len() > SHOWN {
        list.push_str(&format!(", … ({} in all)", header.len()));
    }
    let hint = crate::scene::nearest(name, header).map_or(String::new(), |n| format!("; did you mean '{n}'?"));
    format!("no column '{name}' (its columns: {list}){hint}")
}

/// The cause of a CSV error without its position (reported separately).
fn cause(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
            format!("{len} fields where the header has {expected_len}")
        }
        csv::ErrorKind::Utf8 { .. } => "not valid UTF-8".into(),
        csv::ErrorKind::Io(io) => io.to_string(),
        _ => e.to_string(),
    }
}
