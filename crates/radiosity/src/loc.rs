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
