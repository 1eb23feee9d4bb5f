//! Scene loading errors. Each names the file and, where the problem has a place in it, the line
//! and column, with the offending line quoted.

use std::ops::Range;

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
}

impl SceneError {
    /// An error at byte range `span` of `text` (the contents of `path`).
    pub fn at(path: &str, text: &str, span: Range<usize>, message: impl Into<String>) -> Self {
        let (line, column) = line_column(text, span.start);
        let line_text = text.lines().nth(line - 1).unwrap_or("");
        let width = span.end.saturating_sub(span.start).clamp(1, line_text.len().saturating_sub(column - 1).max(1));
        let gutter = line.to_string().len();
        let snippet = format!(
            "{:gutter$} |\n{line} | {line_text}\n{:gutter$} | {}{}",
            "",
            "",
            " ".repeat(line_text.chars().take(column - 1).count()),
            "^".repeat(width.min(80)),
        );
        SceneError::At { path: path.to_string(), line, column, message: message.into(), snippet }
    }

    /// The message without location (for tests and short reports).
    pub fn message(&self) -> String {
        match self {
            SceneError::Read { source, .. } => source.to_string(),
            SceneError::At { message, .. } | SceneError::File { message, .. } => message.clone(),
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
    }
}
