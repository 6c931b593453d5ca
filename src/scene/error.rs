//! Scene errors that name the file, line, column and key.

use std::fmt;
use std::path::PathBuf;

/// One problem found in a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// 1-based line and column of the table or value at fault (0 when unknown).
    pub line: usize,
    pub column: usize,
    /// Dotted path of the key, e.g. `objects[2].radius`.
    pub key: String,
    pub message: String,
}

impl Problem {
    /// A problem at byte `offset` of the scene text `src` (0: no position, e.g. a value
    /// that came from the command line or a default).
    pub fn at(
        src: &str,
        offset: usize,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        let (line, column) = if offset == 0 {
            (0, 0)
        } else {
            line_col(src, offset)
        };
        Problem {
            line,
            column,
            key: key.into(),
            message: message.into(),
        }
    }
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: cannot read scene: {cause}", path.display())]
    Io {
        path: PathBuf,
        // not `source`: the message already holds it, and a chain would repeat it
        cause: std::io::Error,
    },
    #[error("{}", display_problems(path, problems))]
    Invalid {
        path: PathBuf,
        problems: Vec<Problem>,
    },
}

impl SceneError {
    /// The problems found (empty for I/O errors).
    pub fn problems(&self) -> &[Problem] {
        match self {
            SceneError::Io { .. } => &[],
            SceneError::Invalid { problems, .. } => problems,
        }
    }
}

fn display_problems(path: &std::path::Path, problems: &[Problem]) -> String {
    let mut out = String::new();
    for (i, p) in problems.iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&p.to_string_in(path));
    }
    out
}

impl Problem {
    fn to_string_in(&self, path: &std::path::Path) -> String {
        let key = if self.key.is_empty() {
            String::new()
        } else {
            format!("{}: ", self.key)
        };
        if self.line == 0 {
            format!("{}: {key}{}", path.display(), self.message)
        } else {
            format!(
                "{}:{}:{}: {key}{}",
                path.display(),
                self.line,
                self.column,
                self.message
            )
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.to_string_in(std::path::Path::new("<scene>")))
    }
}

/// 1-based (line, column) of a byte offset in `src`.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(src.len());
    while !src.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &src[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(offset, |nl| offset - nl - 1) + 1;
    (line, col)
}

/// For serde's "unknown field `x`, expected one of `a`, `b`" (and "unknown variant"): the
/// expected name nearest to the unknown one, when it is close enough to be a typo (edit
/// distance at most a third of its length, and at least 1).
pub fn did_you_mean(message: &str) -> Option<String> {
    let rest = message
        .strip_prefix("unknown field `")
        .or_else(|| message.strip_prefix("unknown variant `"))?;
    let (unknown, rest) = rest.split_once('`')?;
    let expected = rest.split_once("expected")?.1;
    let candidates = expected.split('`').skip(1).step_by(2);
    let (best, distance) = candidates
        .map(|c| (c, strsim::damerau_levenshtein(unknown, c)))
        .min_by_key(|&(_, d)| d)?;
    (distance <= (unknown.chars().count() / 3).max(1)).then(|| best.to_string())
}
