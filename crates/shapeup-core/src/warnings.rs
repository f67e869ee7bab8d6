//! Things that were dropped, split or recomputed on the way through shapeup, counted.
//!
//! Nothing changes silently: each kind of change (faces left out of the triangulation,
//! polygons triangulated, normals recomputed, attributes a format cannot hold, vertices an
//! output cannot keep…) is one [`Warning`] with a count and a first example. The command line
//! prints each once as one line on stderr and lists them under `warnings` in `--report` JSON.

use std::fmt;
use std::path::{Path, PathBuf};

/// One kind of change, counted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// A stable identifier (`polygons_triangulated`, `normals_recomputed`, …).
    pub kind: String,
    /// What happened, as a plural noun phrase that follows the count ("polygons with more than
    /// 3 corners triangulated for the solver").
    pub message: String,
    /// How many times.
    pub count: usize,
    /// The first occurrence ("face 12 (4 corners)").
    pub first: String,
    /// The file it concerns, if any.
    pub file: Option<PathBuf>,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        write!(f, "{} {}", self.count, self.message)?;
        if !self.first.is_empty() {
            write!(f, " (first: {})", self.first)?;
        }
        Ok(())
    }
}

/// Warnings, one per kind (and file), in the order they first occurred.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Warnings {
    list: Vec<Warning>,
}

impl Warnings {
    /// None yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counts one occurrence of `kind`; `first` describes it and is called only for the first.
    pub fn add(&mut self, kind: &str, message: &str, first: impl FnOnce() -> String) {
        self.add_many(kind, message, 1, first);
    }

    /// Counts `count` occurrences of `kind` at once (nothing when `count` is 0).
    pub fn add_many(&mut self, kind: &str, message: &str, count: usize, first: impl FnOnce() -> String) {
        if count == 0 {
            return;
        }
        match self.list.iter_mut().find(|w| w.kind == kind && w.file.is_none()) {
            Some(w) => w.count += count,
            None => self.list.push(Warning {
                kind: kind.to_owned(),
                message: message.to_owned(),
                count,
                first: first(),
                file: None,
            }),
        }
    }

    /// Names `to` instead of `from` in the warnings that name `from` (a file written under a
    /// staging name, said under the name it will have).
    pub fn renamed(mut self, from: &Path, to: &Path) -> Self {
        for w in self.list.iter_mut().filter(|w| w.file.as_deref() == Some(from)) {
            w.file = Some(to.to_path_buf());
        }
        self
    }

    /// Names `file` in every warning that names none yet.
    pub fn for_file(mut self, file: &Path) -> Self {
        for w in self.list.iter_mut().filter(|w| w.file.is_none()) {
            w.file = Some(file.to_path_buf());
        }
        self
    }

    /// Adds `other`'s warnings; one of the same kind and file adds its count.
    pub fn extend(&mut self, other: Warnings) {
        for w in other.list {
            match self.list.iter_mut().find(|o| o.kind == w.kind && o.file == w.file) {
                Some(o) => o.count += w.count,
                None => self.list.push(w),
            }
        }
    }

    /// The count of `kind` (0 if it never occurred), over all files.
    pub fn count(&self, kind: &str) -> usize {
        self.list.iter().filter(|w| w.kind == kind).map(|w| w.count).sum()
    }

    /// Every warning, in order.
    pub fn iter(&self) -> impl Iterator<Item = &Warning> {
        self.list.iter()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Number of kinds.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// As JSON: `[{"kind", "count", "message", "first", "file"}, …]`.
    pub fn to_json(&self) -> serde_json::Value {
        self.list
            .iter()
            .map(|w| {
                serde_json::json!({
                    "kind": w.kind,
                    "count": w.count,
                    "message": w.message,
                    "first": w.first,
                    "file": w.file.as_ref().map(|f| f.display().to_string()),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_once_per_kind_and_keeps_the_first_example() {
        let mut w = Warnings::new();
        w.add("a", "things dropped", || "thing 3".into());
        w.add("a", "things dropped", || unreachable!("only the first is described"));
        w.add_many("b", "others", 0, || unreachable!("zero is nothing"));
        assert_eq!(w.len(), 1);
        assert_eq!(w.count("a"), 2);
        let w = w.for_file(Path::new("m.obj"));
        let line = w.iter().next().map(ToString::to_string).unwrap_or_default();
        assert_eq!(line, "m.obj: 2 things dropped (first: thing 3)");
        assert_eq!(w.to_json()[0]["count"], 2);
    }
}
