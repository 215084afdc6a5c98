//! Shared reader of the keyframed animation files: `k <time>` lines (all first, ascending), then
//! one `<tag> <keyframeIndex> v1 … vn` record per element; the element index is implicit (order
//! of the records of that keyframe).

use std::path::Path;

use super::error::ParseError;
use super::text::{Line, lines};

/// Parsed keyframes: `records[k][e]` = the values of element e in keyframe k.
pub(crate) struct Keyframed {
    pub times: Vec<f64>,
    pub records: Vec<Vec<Vec<f64>>>,
    /// Line of every record, same shape as `records`.
    pub record_lines: Vec<Vec<usize>>,
}

/// Parses a keyframed file. `header` sees every line before the first `k` line.
/// Every keyframe must have exactly `per_keyframe` records of `values` numbers.
pub(crate) fn parse_keyframed(
    data: &[u8],
    source: &Path,
    tag: &str,
    values: usize,
    per_keyframe: usize,
    element: &str,
    mut header: impl FnMut(&Line<'_>),
) -> Result<Keyframed, ParseError> {
    let mut times: Vec<f64> = Vec::new();
    let mut time_lines: Vec<usize> = Vec::new();
    let mut records: Vec<Vec<Vec<f64>>> = Vec::new();
    let mut record_lines: Vec<Vec<usize>> = Vec::new();
    let mut any_record = false;
    let mut last_line = 0;
    for line in lines(data, source) {
        let line = line?;
        last_line = line.number;
        let mut t = line.tokens();
        match t.next_raw() {
            Some("k") => {
                if any_record {
                    return Err(line.invalid(format!(
                        "'k' line after the first '{tag}' line: all keyframe times must come first"
                    )));
                }
                let time = t.f64("keyframe time (seconds)")?;
                t.end()?;
                if let Some(&previous) = times.last()
                    && time <= previous
                {
                    return Err(line.invalid(format!(
                        "keyframe time {time} is not after the previous one ({previous}): times must increase"
                    )));
                }
                times.push(time);
                time_lines.push(line.number);
                records.push(Vec::new());
                record_lines.push(Vec::new());
            }
            Some(first) if first == tag => {
                any_record = true;
                let k = t.usize("keyframe index")?;
                if k >= times.len() {
                    return Err(line.out_of_range("keyframe", k as i64, times.len()));
                }
                if records[k].len() == per_keyframe {
                    return Err(line.invalid(format!(
                        "keyframe {k} already has {per_keyframe} {element} (one '{tag}' line each)"
                    )));
                }
                let mut v = Vec::with_capacity(values);
                for _ in 0..values {
                    v.push(t.f64("keyframe value")?);
                }
                t.end()?;
                records[k].push(v);
                record_lines[k].push(line.number);
            }
            _ => {
                if times.is_empty() {
                    header(&line);
                }
            }
        }
    }
    if times.is_empty() {
        return Err(ParseError::Malformed {
            path: source.to_path_buf(),
            line: last_line.max(1),
            expected: "at least one 'k <time>' line".into(),
            found: "end of file".into(),
        });
    }
    for (k, r) in records.iter().enumerate() {
        if r.len() != per_keyframe {
            return Err(ParseError::Invalid {
                path: source.to_path_buf(),
                line: time_lines[k],
                message: format!(
                    "keyframe {k} has {} '{tag}' lines but there are {per_keyframe} {element}",
                    r.len()
                ),
            });
        }
    }
    Ok(Keyframed {
        times,
        records,
        record_lines,
    })
}
