//! What the flame reader's parts share: the error type, the text as parsed with the map back
//! to the file's lines and columns, the messages about one flame ([`Ctx`]), and numbers read as
//! flam3 reads them.

use std::fmt::Display;

/// A flame file that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum FlameError {
    #[error("cannot read {file}: {source}")]
    Io { file: String, source: std::io::Error },
    #[error("{file} is {size_bytes} bytes, more than the {limit_bytes} bytes a flame file may have")]
    TooLarge { file: String, size_bytes: u64, limit_bytes: u64 },
    #[error("{file}:{line}:{column}: {message}")]
    At { file: String, line: u32, column: u32, message: String },
    #[error("{file}: {message}")]
    File { file: String, message: String },
}

/// The text as parsed (wrapped in a synthetic root) and the map back to the original's lines.
pub(super) struct Source {
    pub(super) wrapped: String,
    /// Byte offset in the original where the root's open tag was inserted.
    insert_at: usize,
    original_len: usize,
    /// Byte offsets of the original's line starts.
    line_starts: Vec<usize>,
    original: String,
}

const ROOT_OPEN: &str = "<nlifs-flame-file>";
const ROOT_CLOSE: &str = "</nlifs-flame-file>";

impl Source {
    pub(super) fn wrap(text: &str) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // After the XML declaration (it must come first), before anything else.
        let trimmed = text.trim_start();
        let insert_at = if trimmed.starts_with("<?xml") {
            let decl_start = text.len() - trimmed.len();
            trimmed.find("?>").map_or(0, |end| decl_start + end + 2)
        } else {
            0
        };
        let (head, tail) = text.split_at(insert_at);
        // A DOCTYPE must stay before the root: such a file (one root by its DTD) is not wrapped.
        let wrap = !tail.contains("<!DOCTYPE");
        let wrapped = if wrap { format!("{head}{ROOT_OPEN}{tail}{ROOT_CLOSE}") } else { text.to_string() };
        let line_starts = std::iter::once(0)
            .chain(text.bytes().enumerate().filter(|(_, b)| *b == b'\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            wrapped,
            insert_at: if wrap { insert_at } else { usize::MAX },
            original_len: text.len(),
            line_starts,
            original: text.to_string(),
        }
    }

    /// The original's byte offset of a byte offset in the wrapped text.
    fn original_offset(&self, wrapped_offset: usize) -> usize {
        let o = if wrapped_offset >= self.insert_at.saturating_add(ROOT_OPEN.len()) {
            wrapped_offset - ROOT_OPEN.len()
        } else {
            wrapped_offset.min(self.insert_at)
        };
        o.min(self.original_len)
    }

    /// The original's byte offset of a 1-based (row, column in chars) of the wrapped text.
    pub(super) fn offset_of(&self, row: u32, col: u32) -> usize {
        let mut line_start = 0;
        for _ in 1..row {
            match self.wrapped[line_start..].find('\n') {
                Some(n) => line_start += n + 1,
                None => break,
            }
        }
        let in_line = self.wrapped[line_start..]
            .char_indices()
            .nth(col.saturating_sub(1) as usize)
            .map_or(self.wrapped.len() - line_start, |(i, _)| i);
        self.original_offset(line_start + in_line)
    }

    /// 1-based line and column (in chars) of an original byte offset.
    pub(super) fn line_col(&self, offset: usize) -> (u32, u32) {
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let end = offset.min(self.original.len());
        let column = self.original.get(start..end).map_or(end - start, |s| s.chars().count()) + 1;
        (line as u32, column as u32)
    }

    /// Line and column of a node of the parsed document.
    pub(super) fn node_pos(&self, node: roxmltree::Node) -> (u32, u32) {
        self.line_col(self.original_offset(node.range().start))
    }

    /// Line and column of an attribute's value.
    pub(super) fn attr_pos(&self, attr: &roxmltree::Attribute) -> (u32, u32) {
        self.line_col(self.original_offset(attr.range_value().start))
    }
}

/// Messages about one flame: its label ("flame 'name' (#2)") and the file's positions.
pub(super) struct Ctx<'a> {
    pub file: &'a str,
    pub source: &'a Source,
    pub flame: String,
    pub warnings: &'a mut Vec<String>,
}

impl Ctx<'_> {
    pub fn error_at(&self, (line, column): (u32, u32), what: impl Display) -> FlameError {
        FlameError::At { file: self.file.into(), line, column, message: format!("{}: {what}", self.flame) }
    }

    pub fn error(&self, node: roxmltree::Node, what: impl Display) -> FlameError {
        self.error_at(self.source.node_pos(node), what)
    }

    pub fn attr_error(&self, attr: &roxmltree::Attribute, what: impl Display) -> FlameError {
        self.error_at(self.source.attr_pos(attr), format!("attribute {}: {what}", attr.name()))
    }

    pub fn warn(&mut self, node: roxmltree::Node, what: impl Display) {
        let (line, _) = self.source.node_pos(node);
        self.warnings.push(format!("{}:{line}: {}: {what}", self.file, self.flame));
    }
}

/// A number as flam3's `strtod` reads one (surrounding blanks allowed, `nan` and `inf` too).
pub(super) fn number(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok()
}

/// Whitespace-separated numbers.
pub(super) fn numbers(s: &str) -> Option<Vec<f64>> {
    s.split_whitespace().map(number).collect()
}

/// An attribute's number, or an error naming it.
pub(super) fn attr_number(ctx: &Ctx, attr: &roxmltree::Attribute) -> Result<f64, FlameError> {
    number(attr.value()).ok_or_else(|| ctx.attr_error(attr, format!("'{}' is not a number", attr.value())))
}

/// An attribute's integer (flam3's `strtol`; an integral decimal like `2.0` is taken too).
pub(super) fn attr_int(ctx: &Ctx, attr: &roxmltree::Attribute) -> Result<i64, FlameError> {
    let v = attr.value().trim();
    v.parse::<i64>()
        .ok()
        .or_else(|| number(v).filter(|x| x.fract() == 0.0 && x.abs() < 1e15).map(|x| x as i64))
        .ok_or_else(|| ctx.attr_error(attr, format!("'{v}' is not an integer")))
}

/// Exactly `n` numbers, or an error naming the attribute.
pub(super) fn attr_numbers(ctx: &Ctx, attr: &roxmltree::Attribute, n: usize) -> Result<Vec<f64>, FlameError> {
    match numbers(attr.value()) {
        Some(v) if v.len() == n => Ok(v),
        _ => Err(ctx.attr_error(attr, format!("expected {n} numbers, found '{}'", attr.value()))),
    }
}
