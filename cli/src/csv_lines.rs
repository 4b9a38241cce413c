//! What the small comma-separated files fovea reads have in common (gaze traces, camera paths, views
//! files): a UTF-8 byte-order mark is skipped, a header is recognised by its column names (not by
//! "the first field is not a number"), and a file separated by semicolons, tabs or spaces is named
//! as such instead of failing on a field count.

/// `text` without a leading UTF-8 byte-order mark (spreadsheet exports write one).
#[must_use]
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The separator a line without commas uses instead, by name, where it splits the line into one of
/// `field_counts` fields (`;`, tabs, spaces).
#[must_use]
pub fn other_separator(line: &str, field_counts: &[usize]) -> Option<&'static str> {
    let line = line.trim();
    if line.contains(',') {
        return None;
    }
    let fits = |parts: std::str::Split<'_, char>| {
        field_counts.contains(&parts.filter(|p| !p.trim().is_empty()).count())
    };
    if fits(line.split(';')) {
        Some("semicolons")
    } else if line.contains('\t') && fits(line.split('\t')) {
        Some("tabs")
    } else if fits(line.split(' ')) {
        Some("spaces")
    } else {
        None
    }
}

/// The header of a file whose columns are `columns` (each column's accepted names, the first being
/// the one the documentation uses), for messages: `frame,eye_x,eye_y`.
fn header_text(columns: &[&[&str]]) -> String {
    columns
        .iter()
        .map(|names| names[0])
        .collect::<Vec<_>>()
        .join(",")
}

/// Reads the first line with content of a file whose columns are `columns`: `Ok(true)` for a header
/// naming them in order (case and spaces aside), `Ok(false)` for a data line (its first field is a
/// number), and otherwise an error that says why the line is neither: other separators, the right
/// names in another order, or a line that is not a header at all. `what` names the file's kind
/// ("a camera path").
pub fn is_header(line: &str, columns: &[&[&str]], what: &str) -> Result<bool, String> {
    let fields: Vec<String> = line
        .split(',')
        .map(|f| f.trim().to_ascii_lowercase())
        .collect();
    let expected = header_text(columns);
    if fields.len() == 1 {
        if let Some(sep) = other_separator(line, &[columns.len()]) {
            return Err(format!(
                "'{line}': the fields are separated by {sep}; {what} separates them by commas \
                 ({expected})"
            ));
        }
    }
    if fields[0].parse::<f64>().is_ok() {
        return Ok(false);
    }
    let named = |f: &String, names: &[&str]| names.iter().any(|n| f == n);
    if fields.len() == columns.len() && fields.iter().zip(columns).all(|(f, n)| named(f, n)) {
        return Ok(true);
    }
    let known = fields
        .iter()
        .filter(|f| columns.iter().any(|n| named(f, n)))
        .count();
    if fields.len() == columns.len() && known == columns.len() {
        Err(format!(
            "header '{line}': {what} names its columns {expected}, in that order"
        ))
    } else {
        Err(format!(
            "'{line}' is neither a header ({expected}) nor a line of numbers"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLUMNS: &[&[&str]] = &[&["frame"], &["x", "ex"], &["y", "ey"]];

    #[test]
    fn headers_are_recognised_by_their_names() {
        assert_eq!(is_header("frame,x,y", COLUMNS, "a file"), Ok(true));
        assert_eq!(is_header(" Frame , EX , ey ", COLUMNS, "a file"), Ok(true));
        assert_eq!(is_header("0,1,2", COLUMNS, "a file"), Ok(false));
        assert_eq!(is_header("-1e3,1,2", COLUMNS, "a file"), Ok(false));
        for (line, needle) in [
            ("frame,y,x", "in that order"),
            ("time,x,y", "neither a header (frame,x,y)"),
            ("garbage", "neither a header"),
            ("0;1;2", "separated by semicolons"),
            ("0\t1\t2", "separated by tabs"),
            ("0 1 2", "separated by spaces"),
            ("frame;x;y", "separated by semicolons"),
        ] {
            let e = is_header(line, COLUMNS, "a file").unwrap_err();
            assert!(e.contains(needle), "{line:?}: {e}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_skipped_and_only_at_the_start() {
        assert_eq!(strip_bom("\u{feff}frame,x,y"), "frame,x,y");
        assert_eq!(strip_bom("frame,\u{feff}x"), "frame,\u{feff}x");
    }
}
