//! Numbers in delimited text lines: the fast path of imukit's line readers
//! (`python/imukit/io/_lines.py`, issue 17: 3 M EuRoC lines took 40 s and 4.3 GB as Python objects).
//!
//! [`parse_block`] reads a block of whole lines and keeps the *plain* ones as rows: the right
//! number of fields, every field read a finite decimal number, the stamp field an exact integer
//! (or seconds with nine decimals) when asked. Blank lines and `#` lines are passed over. Every
//! other line is *deferred*: handed back by number and offset for the Python reader, whose rules
//! and messages are the reference. The grammar accepted here is a subset of the readers' (Python's
//! `float()` on ASCII fields without `_`, and the integer stamps), and Rust's float parsing is correctly rounded as Python's is, so a line read here gives the same numbers,
//! bit for bit, as the Python reader would.

/// How fields are separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Separator {
    /// One byte (`,`, `;`, tab), as Python's `str.split(sep)`.
    Byte(u8),
    /// Runs of spaces and tabs, as Python's `str.split()`.
    Whitespace,
}

/// The exact integer nanoseconds the stamp field is also read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StampForm {
    /// None: the stamp is a float like the other fields.
    Float,
    /// An integer of at most 20 digits and a sign, within int64 (EuRoC's `1403636579758555392`).
    Integer,
    /// Seconds with exactly nine decimals (`1403636579.758555392`, as TUM files written from `t_ns`).
    NineDecimals,
}

/// The stamp of a row whose stamp has not the exact form (never an exact stamp: those are above it).
pub const INEXACT: i64 = i64::MIN;

/// What a line must hold to be read here.
#[derive(Clone, Copy, Debug)]
pub struct Layout<'a> {
    /// The field separator.
    pub separator: Separator,
    /// The number of fields of every line.
    pub width: usize,
    /// The fields read as floats, in the order of a row's values.
    pub columns: &'a [usize],
    /// The field holding the stamp.
    pub stamp_column: usize,
    /// The exact form of the stamp.
    pub stamp: StampForm,
    /// Whether a line whose stamp lacks that form is deferred (true), or read with `exact` false.
    pub stamp_required: bool,
    /// Whether a line ending in the (one-byte) separator has that empty last field dropped (`a;b;c;`
    /// read as three fields), as the generic CSV reader does for a file written that way.
    pub trailing: bool,
}

/// The rows and deferred lines of one block.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Block {
    /// The 1-based line number of each row.
    pub lines: Vec<u64>,
    /// The byte offset in the block of each row's line.
    pub offsets: Vec<u64>,
    /// `lines.len() × columns.len()` values, row-major.
    pub values: Vec<f64>,
    /// The exact stamp of each row, [`INEXACT`] for a stamp without the form (empty for
    /// [`StampForm::Float`]).
    pub stamps: Vec<i64>,
    /// Whether every row's stamp had the exact form (always true for [`StampForm::Float`]).
    pub exact: bool,
    /// The line numbers of the deferred lines.
    pub deferred_lines: Vec<u64>,
    /// The byte offsets of the deferred lines.
    pub deferred_offsets: Vec<u64>,
    /// The number of lines in the block (a last line without newline counts).
    pub line_count: u64,
}

/// The rows and deferred lines of `text`, whole lines numbered from `first_line`.
pub fn parse_block(text: &[u8], first_line: u64, layout: &Layout<'_>) -> Block {
    let mut block = Block {
        exact: true,
        ..Block::default()
    };
    let mut number = first_line;
    let mut start = 0usize;
    let mut fields: Vec<&[u8]> = Vec::with_capacity(layout.width + 1);
    let mut row: Vec<f64> = Vec::with_capacity(layout.columns.len());
    while start < text.len() {
        let end = text[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |k| start + k);
        let line = trim(&text[start..end]);
        if !(line.is_empty() || line[0] == b'#') {
            match read_line(line, layout, &mut fields, &mut row) {
                Some(stamp) => {
                    block.lines.push(number);
                    block.offsets.push(start as u64);
                    block.values.extend_from_slice(&row);
                    match stamp {
                        Stamp::Exact(ns) => block.stamps.push(ns),
                        Stamp::Inexact => {
                            block.exact = false;
                            block.stamps.push(INEXACT);
                        }
                        Stamp::Unread => {}
                    }
                }
                None => {
                    block.deferred_lines.push(number);
                    block.deferred_offsets.push(start as u64);
                }
            }
        }
        number += 1;
        start = end + 1;
    }
    block.line_count = number - first_line;
    block
}

enum Stamp {
    Exact(i64),
    Inexact,
    Unread,
}

/// The stamp of a plain line (its values in `row`), or None to defer it.
fn read_line<'t>(line: &'t [u8], layout: &Layout<'_>, fields: &mut Vec<&'t [u8]>, row: &mut Vec<f64>) -> Option<Stamp> {
    // Bytes Python would read otherwise: non-ASCII (Unicode digits and spaces, bad UTF-8), control
    // characters that str.strip() removes, a lone \r (a line break to Python's text files).
    if line.iter().any(|&b| !(b == b'\t' || (b' '..=b'~').contains(&b))) {
        return None;
    }
    let line = match (layout.trailing, layout.separator, line.split_last()) {
        (true, Separator::Byte(sep), Some((&last, rest))) if last == sep => rest,
        _ => line,
    };
    fields.clear();
    match layout.separator {
        Separator::Byte(sep) => fields.extend(line.split(|&b| b == sep).map(trim)),
        Separator::Whitespace => fields.extend(line.split(|&b| b == b' ' || b == b'\t').filter(|f| !f.is_empty())),
    }
    if fields.len() != layout.width {
        return None;
    }
    row.clear();
    for &c in layout.columns {
        let value: f64 = std::str::from_utf8(fields.get(c)?).ok()?.parse().ok()?;
        if !value.is_finite() {
            return None;
        }
        row.push(value);
    }
    let field = fields.get(layout.stamp_column)?;
    let exact = match layout.stamp {
        StampForm::Float => return Some(Stamp::Unread),
        StampForm::Integer => integer(field),
        StampForm::NineDecimals => nine_decimals(field),
    };
    match exact {
        Some(ns) => Some(Stamp::Exact(ns)),
        None if layout.stamp_required => None,
        None => Some(Stamp::Inexact),
    }
}

/// `text` without surrounding spaces, tabs and carriage returns.
fn trim(text: &[u8]) -> &[u8] {
    let blank = |b: &u8| matches!(b, b' ' | b'\t' | b'\r');
    let start = text.iter().position(|b| !blank(b)).unwrap_or(text.len());
    let end = text.iter().rposition(|b| !blank(b)).map_or(start, |k| k + 1);
    &text[start..end]
}

/// `[+-]?[0-9]{1,20}` within int64, as the readers' `integer_stamp`.
fn integer(field: &[u8]) -> Option<i64> {
    let digits = field.strip_prefix(b"+").or(field.strip_prefix(b"-")).unwrap_or(field);
    if digits.is_empty() || digits.len() > 20 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(field)
        .ok()?
        .parse()
        .ok()
        .filter(|&ns| ns != INEXACT)
}

/// `-?[0-9]+\.[0-9]{9}` as integer nanoseconds within int64, as the TUM reader's `exact_ns`.
fn nine_decimals(field: &[u8]) -> Option<i64> {
    let (negative, unsigned) = match field.strip_prefix(b"-") {
        Some(rest) => (true, rest),
        None => (false, field),
    };
    let dot = unsigned.iter().position(|&b| b == b'.')?;
    let (whole, fraction) = (&unsigned[..dot], &unsigned[dot + 1..]);
    if whole.is_empty() || fraction.len() != 9 || !whole.iter().chain(fraction).all(u8::is_ascii_digit) {
        return None;
    }
    let mut ns: i128 = 0;
    for &d in whole.iter().chain(fraction) {
        ns = ns.checked_mul(10)?.checked_add(i128::from(d - b'0'))?;
    }
    i64::try_from(if negative { -ns } else { ns })
        .ok()
        .filter(|&ns| ns != INEXACT)
}

#[cfg(test)]
mod tests {
    use super::*;

    const EUROC: Layout<'static> = Layout {
        separator: Separator::Byte(b','),
        width: 3,
        columns: &[1, 2],
        stamp_column: 0,
        stamp: StampForm::Integer,
        stamp_required: true,
        trailing: false,
    };

    #[test]
    fn plain_lines_are_rows_the_others_deferred() {
        let text = b"#t,a,b\n1403636579758555392,0.1,-2e-3\r\n\n2, 1_0,3\n3,4,5,6\n4,inf,1\n5,1.,.5";
        let block = parse_block(text, 1, &EUROC);
        assert_eq!(block.lines, vec![2, 7]);
        assert_eq!(block.offsets, vec![7, 64]);
        assert_eq!(block.values, vec![0.1, -2e-3, 1.0, 0.5]);
        assert_eq!(block.stamps, vec![1_403_636_579_758_555_392, 5]);
        assert_eq!(block.deferred_lines, vec![4, 5, 6]);
        assert_eq!(block.line_count, 7);
    }

    #[test]
    fn non_ascii_bytes_and_bad_stamps_are_deferred() {
        let block = parse_block(
            "1,2,3\n1.5,2,3\n99999999999999999999,1,2\n1,\u{a0}2,3\n1,\u{661},3\n".as_bytes(),
            10,
            &EUROC,
        );
        assert_eq!(block.lines, vec![10]);
        assert_eq!(block.deferred_lines, vec![11, 12, 13, 14]);
    }

    #[test]
    fn whitespace_and_nine_decimal_stamps() {
        let layout = Layout {
            separator: Separator::Whitespace,
            width: 2,
            columns: &[0, 1],
            stamp_column: 0,
            stamp: StampForm::NineDecimals,
            stamp_required: false,
            trailing: false,
        };
        let block = parse_block(b"  -1.000000001\t 2 \n1.5 3\n", 1, &layout);
        assert_eq!(block.values, vec![-1.000000001, 2.0, 1.5, 3.0]);
        assert_eq!(block.stamps, vec![-1_000_000_001, INEXACT]);
        assert!(!block.exact);
        assert_eq!(nine_decimals(b"9223372036.854775808"), None); // one past int64
        assert_eq!(nine_decimals(b"9223372036.854775807"), Some(i64::MAX));
        assert_eq!(nine_decimals(b"-9223372036.854775808"), None); // INEXACT, read by Python
        assert_eq!(integer(b"-9223372036854775808"), None);
    }

    #[test]
    fn a_trailing_separator_is_dropped_when_asked() {
        let layout = Layout {
            trailing: true,
            ..EUROC
        };
        let block = parse_block(
            b"1,2,3;\n2,4,5,\n3,6,7\n4,8,9,,\n",
            1,
            &Layout {
                separator: Separator::Byte(b','),
                ..layout
            },
        );
        assert_eq!(block.lines, vec![2, 3]);
        assert_eq!(block.values, vec![4.0, 5.0, 6.0, 7.0]);
        assert_eq!(block.deferred_lines, vec![1, 4]);
        assert_eq!(parse_block(b"2,4,5,\n", 1, &EUROC).deferred_lines, vec![1]);
    }
}
