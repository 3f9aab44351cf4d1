//! Where things are in a TOML file: dotted field paths (`objects[2].material`)
//! and 1-based line numbers, for errors that name both. Built once per file
//! from `toml`'s spanned parse tree; serde errors (which carry a byte span but
//! not an array index) and semantic errors (which know the path but not the
//! line) are located through it. Syntax errors, where no tree exists, are
//! located from the enclosing table header and the key on the failing line.

use std::ops::Range;
use std::path::Path;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::error::FieldError;

/// One key or array element of the document.
#[derive(Clone, Debug)]
struct Entry {
    /// Dotted path, with `[i]` for array elements.
    path: String,
    /// Byte range of the key (of the element for array elements).
    key: Range<usize>,
    /// Byte range of the value.
    value: Range<usize>,
}

/// Maps dotted field paths to lines and byte spans to field paths.
#[derive(Clone, Debug, Default)]
pub struct Locator {
    /// Byte offset of the start of each line.
    line_starts: Vec<usize>,
    entries: Vec<Entry>,
    /// Byte range `toml` gives the document itself, and so the errors about
    /// its top-level fields: `0..0`, which a table header at offset 0 covers.
    document: Range<usize>,
}

impl Locator {
    /// Indexes the parsed document `root` of `text`.
    pub fn new(text: &str, root: &Spanned<DeTable<'_>>) -> Self {
        let mut locator = Self {
            line_starts: line_starts(text),
            entries: Vec::new(),
            document: root.span(),
        };
        locator.walk_table("", root.get_ref());
        locator
    }

    /// A locator for `text` in a format other than TOML (such as Mitsuba
    /// XML): each field is a dotted path with the byte range that defines it.
    pub fn from_spans(text: &str, spans: impl IntoIterator<Item = (String, Range<usize>)>) -> Self {
        let entries = spans
            .into_iter()
            .map(|(path, range)| Entry {
                path,
                key: range.clone(),
                value: range,
            })
            .collect();
        Self {
            line_starts: line_starts(text),
            entries,
            ..Self::default()
        }
    }

    fn walk_table(&mut self, prefix: &str, table: &DeTable<'_>) {
        for (key, value) in table {
            let path = join(prefix, key.get_ref());
            self.push(path, key.span(), value);
        }
    }

    fn push(&mut self, path: String, key: Range<usize>, value: &Spanned<DeValue<'_>>) {
        self.entries.push(Entry {
            path: path.clone(),
            key,
            value: value.span(),
        });
        match value.get_ref() {
            DeValue::Table(t) => self.walk_table(&path, t),
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    self.push(format!("{path}[{i}]"), item.span(), item);
                }
            }
            _ => {}
        }
    }

    /// The 1-based line of byte `offset`.
    pub fn line_of_offset(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    /// The line of field `path`, or of its nearest ancestor present in the file.
    pub fn line(&self, path: &str) -> Option<usize> {
        let mut path = path;
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == path) {
                return Some(self.line_of_offset(e.key.start));
            }
            path = &path[..path.rfind(['.', '['])?];
        }
    }

    /// The innermost field whose key or value covers `span`; the top level
    /// (`""`) for the span of the document itself.
    fn path_at(&self, span: &Range<usize>) -> Option<&str> {
        if *span == self.document {
            return Some("");
        }
        let covers = |r: &Range<usize>| r.start <= span.start && span.end <= r.end;
        self.entries
            .iter()
            .flat_map(|e| [(e, &e.key), (e, &e.value)])
            .filter(|(_, r)| covers(r))
            .rev() // children follow their parent: on a tie, the innermost wins
            .min_by_key(|(_, r)| r.len())
            .map(|(e, _)| e.path.as_str())
    }

    /// A located error for a failed deserialization of this document.
    pub fn serde_error(&self, file: &Path, err: &toml::de::Error) -> FieldError {
        let span = err.span();
        let mut field = span
            .as_ref()
            .and_then(|s| self.path_at(s))
            .unwrap_or_default()
            .to_owned();
        let message = err.message();
        if let Some(name) = quoted_after(message, "missing field `")
            .or_else(|| quoted_after(message, "unknown field `"))
            .filter(|name| field.rsplit(['.', ']']).next() != Some(name))
        {
            field = join(&field, name);
        }
        let error = FieldError::new(file, document_if_empty(field), message);
        match span {
            Some(s) => error.at_line(self.line_of_offset(s.start)),
            None => error,
        }
    }
}

/// A located error for a TOML syntax error in `text`.
pub fn syntax_error(file: &Path, text: &str, err: &toml::de::Error) -> FieldError {
    let message = err.message().to_owned();
    let Some(span) = err.span() else {
        return FieldError::new(file, "document", message);
    };
    let starts = line_starts(text);
    let line = starts.partition_point(|&s| s <= span.start).max(1);
    // Unclosed constructs fail at the end of the file: blame the last line with content.
    let lines: Vec<&str> = text.lines().collect();
    let line = (1..=line.min(lines.len()))
        .rev()
        .find(|&l| !is_blank(lines[l - 1]))
        .unwrap_or(line);
    let field = field_at_line(text, line);
    FieldError::new(file, document_if_empty(field), message).at_line(line)
}

/// The dotted path of whatever line `line` (1-based) defines: the last table
/// header at or before it (`[[x]]` counted as `x[i]`), plus the key on the line.
fn field_at_line(text: &str, line: usize) -> String {
    let mut table = String::new();
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut key = String::new();
    for (i, raw) in text.lines().take(line).enumerate() {
        let l = raw.trim();
        key.clear();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.split("]]").next()) {
            let name = name.trim().to_owned();
            let n = match counts.iter_mut().find(|(k, _)| *k == name) {
                Some((_, n)) => {
                    *n += 1;
                    *n
                }
                None => {
                    counts.push((name.clone(), 0));
                    0
                }
            };
            table = format!("{name}[{n}]");
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.split(']').next()) {
            table = name.trim().to_owned();
        } else if i + 1 == line {
            key = l.split('=').next().unwrap_or_default().trim().to_owned();
        }
    }
    if key.contains(char::is_whitespace) || key.starts_with('#') {
        key.clear();
    }
    join(&table, &key)
}

/// Whether a line holds nothing but whitespace or a comment.
fn is_blank(line: &str) -> bool {
    let l = line.trim_start();
    l.is_empty() || l.starts_with('#')
}

fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

fn join(prefix: &str, key: &str) -> String {
    match (prefix.is_empty(), key.is_empty()) {
        (true, _) => key.to_owned(),
        (false, true) => prefix.to_owned(),
        (false, false) => format!("{prefix}.{key}"),
    }
}

fn document_if_empty(field: String) -> String {
    if field.is_empty() {
        "document".to_owned()
    } else {
        field
    }
}

/// The text between `prefix` and the next backquote in `message`.
fn quoted_after<'a>(message: &'a str, prefix: &str) -> Option<&'a str> {
    let rest = &message[message.find(prefix)? + prefix.len()..];
    rest.split('`').next()
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    use super::*;
    use crate::desc::SceneDesc;

    const TEXT: &str = "[camera]\nfov = 40\n\n[[objects]]\nname = \"a\"\n\n[[objects]]\nname = \"b\"\nrotate = [{ axis = [0, 1, 0], angle = 5 }]\n";

    fn locator() -> Locator {
        let root = DeTable::parse(TEXT).expect("valid TOML");
        Locator::new(TEXT, &root)
    }

    #[test]
    fn fields_map_to_their_lines_and_missing_fields_to_their_table() {
        let l = locator();
        assert_eq!(l.line("camera.fov"), Some(2));
        assert_eq!(l.line("objects[1].name"), Some(8));
        assert_eq!(l.line("objects[1].rotate[0].angle"), Some(9));
        assert_eq!(
            l.line("objects[1].material"),
            Some(7),
            "falls back to the [[objects]] header"
        );
        assert_eq!(l.line("render.spp"), None);
    }

    #[test]
    fn spans_map_to_the_innermost_field() {
        let l = locator();
        let at = |needle: &str| {
            let start = TEXT.find(needle).expect("needle in text");
            l.path_at(&(start..start + needle.len())).map(str::to_owned)
        };
        assert_eq!(at("\"b\"").as_deref(), Some("objects[1].name"));
        assert_eq!(at("5").as_deref(), Some("objects[1].rotate[0].angle"));
        assert_eq!(at("40").as_deref(), Some("camera.fov"));
    }

    /// The field a failed deserialization of scene file `text` names.
    fn scene_error_field(text: &str) -> String {
        let root = DeTable::parse(text).expect("valid TOML");
        let locator = Locator::new(text, &root);
        let err = SceneDesc::deserialize(toml::de::Deserializer::from(root))
            .expect_err("an invalid scene");
        locator.serde_error(Path::new("x.toml"), &err).field
    }

    #[test]
    fn missing_top_level_fields_are_named_at_the_top_level_whatever_table_comes_first() {
        for text in [
            "",
            "[render]\nspp = 4\n",
            "\n[render]\nspp = 4\n",
            "[render]\nspp = 4\n\n[[objects]]\nname = \"a\"\nshape = \"sphere\"\nmaterial = \"m\"\n",
            "[materials.m]\ntype = \"diffuse\"\n",
            "[[objects]]\nname = \"a\"\nshape = \"sphere\"\nmaterial = \"m\"\n",
            "render = { spp = 4 }\n",
        ] {
            assert_eq!(scene_error_field(text), "camera", "{text:?}");
        }
    }

    #[test]
    fn missing_fields_of_a_table_at_the_start_are_named_inside_it() {
        let camera = "[camera]\norigin = [0, 0, 1]\ntarget = [0, 0, 0]\nresolution = [8, 8]\n";
        assert_eq!(
            scene_error_field("[camera]\ntarget = [0, 0, 0]\n"),
            "camera.origin"
        );
        assert_eq!(
            scene_error_field(&format!("[materials.m]\nior = 1.5\n{camera}")),
            "materials.m.type"
        );
        assert_eq!(
            scene_error_field(&format!("[[objects]]\nname = \"a\"\n{camera}")),
            "objects[0].material"
        );
    }

    #[test]
    fn syntax_errors_are_located_by_header_and_key() {
        assert_eq!(field_at_line(TEXT, 8), "objects[1].name");
        assert_eq!(field_at_line(TEXT, 5), "objects[0].name");
        assert_eq!(field_at_line(TEXT, 7), "objects[1]");
        assert_eq!(field_at_line("not toml at all", 1), "");
        let broken = "[camera]\nfov = [1, 2\n";
        let err = DeTable::parse(broken).expect_err("unclosed array");
        let e = syntax_error(Path::new("x.toml"), broken, &err);
        assert_eq!((e.field.as_str(), e.line), ("camera.fov", Some(2)));
    }
}
