//! Where in the input something is: a file and line (in the manner of pbrt's `FileLoc`), an
//! element of a file, or an element of a scene that has no file. Errors carry one, so that a
//! message names the place without the library knowing how the program reports it.

use std::fmt;
use std::path::{Path, PathBuf};

/// An element of an input, for places that have no line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    /// A polygon, by its index in the scene.
    Polygon(usize),
    /// A face, by its index in the file.
    Face(usize),
    /// A material, by name.
    Material(String),
    /// A byte offset in a binary file.
    Byte(usize),
}

impl fmt::Display for Item {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Item::Polygon(i) => write!(f, "polygon {i}"),
            Item::Face(i) => write!(f, "face {i}"),
            Item::Material(name) => write!(f, "material '{name}'"),
            Item::Byte(offset) => write!(f, "byte {offset}"),
        }
    }
}

/// What an input came from: a file, or a scene made in memory (a built-in scene).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// A file.
    File(PathBuf),
    /// A scene without a file, by name.
    Scene(String),
}

/// A place in the input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileLoc {
    /// The file or scene.
    pub source: Source,
    /// The line (1-based), when known.
    pub line: Option<usize>,
    /// The element, when there is no line.
    pub item: Option<Item>,
}

impl FileLoc {
    /// A file as a whole.
    pub fn file(path: &Path) -> Self {
        Self {
            source: Source::File(path.to_path_buf()),
            line: None,
            item: None,
        }
    }

    /// A line of a file (0 means the file as a whole).
    pub fn line(path: &Path, line: usize) -> Self {
        Self {
            line: (line > 0).then_some(line),
            ..Self::file(path)
        }
    }

    /// A scene without a file.
    pub fn scene(name: &str) -> Self {
        Self {
            source: Source::Scene(name.to_string()),
            line: None,
            item: None,
        }
    }

    /// The same place narrowed to `item`.
    pub fn with_item(mut self, item: Item) -> Self {
        self.item = Some(item);
        self
    }
}

impl fmt::Display for FileLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.source, self.line, &self.item) {
            (Source::File(p), Some(line), _) => write!(f, "{}:{line}", p.display()),
            (Source::File(p), None, Some(item)) => write!(f, "{} ({item})", p.display()),
            (Source::File(p), None, None) => write!(f, "{}", p.display()),
            (Source::Scene(name), _, Some(item)) => write!(f, "scene '{name}' {item}"),
            (Source::Scene(name), _, None) => write!(f, "scene '{name}'"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_read_as_before() {
        let p = Path::new("a/b.obj");
        assert_eq!(FileLoc::line(p, 12).to_string(), "a/b.obj:12");
        assert_eq!(FileLoc::line(p, 0).to_string(), "a/b.obj");
        assert_eq!(
            FileLoc::file(p).with_item(Item::Face(3)).to_string(),
            "a/b.obj (face 3)"
        );
        assert_eq!(
            FileLoc::scene("cornell")
                .with_item(Item::Polygon(4))
                .to_string(),
            "scene 'cornell' polygon 4"
        );
        assert_eq!(
            FileLoc::scene("cornell")
                .with_item(Item::Material("white".into()))
                .to_string(),
            "scene 'cornell' material 'white'"
        );
    }
}

/// Longest quoted excerpt of the input kept in a message, characters.
pub const MAX_EXCERPT: usize = 40;
/// Longest message kept, characters.
pub const MAX_MESSAGE: usize = 400;

/// `message` with every '…'-quoted excerpt of the input cut to [`MAX_EXCERPT`] characters and
/// the whole to [`MAX_MESSAGE`], so that a hostile file cannot echo a megabyte into an error.
pub fn shorten(message: String) -> String {
    if message.chars().count() <= MAX_EXCERPT {
        return message;
    }
    let mut out = String::with_capacity(message.len().min(MAX_MESSAGE + 8));
    let mut inside = false;
    let mut run = 0usize;
    for c in message.chars() {
        if c == '\'' {
            if inside && run > MAX_EXCERPT {
                out.push('…');
            }
            inside = !inside;
            run = 0;
            out.push(c);
        } else if inside {
            run += 1;
            if run <= MAX_EXCERPT {
                out.push(c);
            }
        } else {
            out.push(c);
        }
    }
    if out.chars().count() > MAX_MESSAGE {
        out = out.chars().take(MAX_MESSAGE).collect::<String>() + "…";
    }
    out
}

#[cfg(test)]
mod shorten_tests {
    use super::*;

    #[test]
    fn long_excerpts_and_messages_are_cut() {
        let long = "x".repeat(1_000_000);
        let m = shorten(format!("malformed number '{long}' in vertex"));
        assert_eq!(
            m,
            format!("malformed number '{}…' in vertex", "x".repeat(MAX_EXCERPT))
        );
        assert!(shorten("y".repeat(5000)).chars().count() <= MAX_MESSAGE + 1);
        assert_eq!(shorten("short 'a' message".into()), "short 'a' message");
    }
}

/// `100 · part / whole` as a percentage with `decimals` decimals, or "an unknown share" where it
/// is not a finite number (a zero or non-finite whole), so that no message says `NaN%`.
pub fn percent(part: f64, whole: f64, decimals: usize) -> String {
    let p = 100.0 * part / whole;
    if p.is_finite() {
        format!("{p:.decimals$}%")
    } else {
        "an unknown share".to_string()
    }
}
