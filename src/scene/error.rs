//! Scene loading errors. Each names the file and, where the problem has a place in it, the line
//! and column, with the offending line quoted.

use std::ops::Range;

/// Characters of a long line quoted around the place of an error.
const SNIPPET_WIDTH: usize = 100;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene file `{path}`: {source}")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}:{column}: {message}\n{snippet}")]
    At { path: String, line: usize, column: usize, message: String, snippet: String },
    #[error("{path}: {message}")]
    File { path: String, message: String },
    /// The load stopped before reading what would not fit in the memory allowed.
    #[error(transparent)]
    Memory(#[from] super::footprint::OverBudget),
}

impl SceneError {
    /// An error at byte range `span` of `text` (the contents of `path`).
    pub fn at(path: &str, text: &str, span: Range<usize>, message: impl Into<String>) -> Self {
        let (line, column) = line_column(text, span.start);
        let line_text = text.lines().nth(line - 1).unwrap_or("");
        let chars: Vec<char> = line_text.chars().collect();
        // Long lines (a whole XML file on one line) are quoted as a window around the column.
        let (from, to) = if chars.len() > SNIPPET_WIDTH {
            let from = (column - 1).saturating_sub(SNIPPET_WIDTH / 2).min(chars.len() - SNIPPET_WIDTH);
            (from, from + SNIPPET_WIDTH)
        } else {
            (0, chars.len())
        };
        let shown: String = chars[from..to].iter().collect();
        let (before, after) = (if from > 0 { "..." } else { "" }, if to < chars.len() { "..." } else { "" });
        let caret_at = before.len() + (column - 1).saturating_sub(from);
        let width = span.end.saturating_sub(span.start).clamp(1, (to + 1).saturating_sub(column).max(1));
        let gutter = line.to_string().len();
        let snippet = format!(
            "{:gutter$} |\n{line} | {before}{shown}{after}\n{:gutter$} | {}{}",
            "",
            "",
            " ".repeat(caret_at),
            "^".repeat(width.min(80)),
        );
        SceneError::At { path: path.to_string(), line, column, message: message.into(), snippet }
    }

    /// The message without location (for tests and short reports).
    pub fn message(&self) -> String {
        match self {
            SceneError::Read { source, .. } => source.to_string(),
            SceneError::At { message, .. } | SceneError::File { message, .. } => message.clone(),
            SceneError::Memory(o) => o.to_string(),
        }
    }

    /// (line, column) when the error has a place in the file.
    pub fn location(&self) -> Option<(usize, usize)> {
        match self {
            SceneError::At { line, column, .. } => Some((*line, *column)),
            _ => None,
        }
    }
}

/// 1-based line and column (in characters) of byte offset `pos`.
pub fn line_column(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let mut pos = pos;
    while !text.is_char_boundary(pos) {
        pos -= 1;
    }
    let before = &text[..pos];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_and_snippet() {
        let text = "a = 1\nradius = -2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 15), (2, 10));
        let e = SceneError::at("s.toml", text, 15..17, "radius must be positive");
        let shown = e.to_string();
        assert!(shown.starts_with("s.toml:2:10: radius must be positive"), "{shown}");
        assert!(shown.contains("radius = -2") && shown.contains("^^"), "{shown}");
        // A very long line is quoted as a window around the column, caret under the place.
        let long = format!("{}<bad>{}", "x".repeat(5000), "y".repeat(5000));
        let e = SceneError::at("l.xml", &long, 5000..5005, "bad");
        let shown = e.to_string();
        assert!(shown.len() < 400, "{} characters", shown.len());
        let lines: Vec<&str> = shown.lines().collect();
        let caret = lines[3].find('^').unwrap();
        assert_eq!(&lines[2][caret..caret + 5], "<bad>", "{shown}");
    }
}
