//! Mitsuba 3 XML → a tree of `Element`s through `roxmltree`: `<default>`
//! parameters substituted for `$name` in every attribute, each element given
//! a dotted field path (`shape[floor].bsdf.reflectance`) registered with its
//! byte range so later errors carry the line. Readers mark what they read
//! (typed property readers are in [`props`](super::props)) so `finish` can
//! reject what nobody read.
//!
//! | path segment | element |
//! |---|---|
//! | `tag[id]`, else `tag[i]` (i-th of its tag among siblings) | plugins: `shape`, `bsdf`, `emitter`, … |
//! | the `name` attribute | properties: `<float name="fov">` → `fov` |
//! | the tag | unnamed properties: `lookat`, `translate`, `ref` |
//! | `.attribute` | an attribute of the element |
//!
//! ```xml
//! <scene version="3.0.0">
//!     <default name="spp" value="16"/>
//!     <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
//! </scene>
//! ```

use std::cell::Cell;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use crate::error::{Error, FieldError, Result};
use crate::fields::Fields;
use crate::fields::Locator;

/// Deepest accepted element nesting (real scenes use fewer than 10 levels).
pub const MAX_DEPTH: usize = 64;

/// One XML element with its attributes (parameters substituted).
#[derive(Debug)]
pub(crate) struct Element {
    /// The tag name.
    pub tag: String,
    /// Dotted field path, used in errors.
    pub path: String,
    attrs: Vec<(String, String)>,
    /// Child elements in document order.
    pub children: Vec<Element>,
    used: Cell<bool>,
}

/// A parsed document: the root element and the locator of its paths.
pub(crate) struct Document {
    /// The `<scene>` element.
    pub root: Element,
    /// Lines of element paths.
    pub locator: Locator,
}

/// Parses `text`; errors (syntax, undefined `$name`, a root other than
/// `<scene>`, nesting deeper than [`MAX_DEPTH`]) name `file` and the line.
pub(crate) fn parse(text: &str, file: &Path) -> Result<Document> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        FieldError::new(file, "document", format!("malformed XML: {e}"))
            .at_line(e.pos().row as usize)
    })?;
    let line = |node: roxmltree::Node| doc.text_pos_at(node.range().start).row as usize;
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        let msg = format!(
            "expected a <scene> root element, found <{}>",
            root.tag_name().name()
        );
        return Err(FieldError::new(file, "document", msg)
            .at_line(line(root))
            .into());
    }
    let mut defaults = HashMap::new();
    for d in root.children().filter(|n| n.has_tag_name("default")) {
        let (Some(name), Some(value)) = (d.attribute("name"), d.attribute("value")) else {
            let msg = "expected name and value attributes";
            return Err(FieldError::new(file, "default", msg)
                .at_line(line(d))
                .into());
        };
        defaults.insert(name.to_owned(), value.to_owned());
    }
    let mut spans = Vec::new();
    let mut builder = Builder {
        file,
        defaults: &defaults,
        spans: &mut spans,
        ids: HashMap::new(),
        line: &line,
    };
    let root = builder.element(root, "scene".into(), 0)?;
    Ok(Document {
        root,
        locator: Locator::from_spans(text, spans),
    })
}

struct Builder<'a, L> {
    file: &'a Path,
    defaults: &'a HashMap<String, String>,
    spans: &'a mut Vec<(String, Range<usize>)>,
    /// Each `id` defined so far: the tag and line of its element.
    ids: HashMap<String, (String, usize)>,
    line: &'a L,
}

impl<L: Fn(roxmltree::Node) -> usize> Builder<'_, L> {
    fn element(&mut self, node: roxmltree::Node, path: String, depth: usize) -> Result<Element> {
        let fail = |msg: String| {
            Error::from(FieldError::new(self.file, &path, msg).at_line((self.line)(node)))
        };
        if depth > MAX_DEPTH {
            return Err(fail(format!(
                "elements nest deeper than {MAX_DEPTH} levels"
            )));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let value = substitute(a.value(), self.defaults).map_err(&fail)?;
            attrs.push((a.name().to_owned(), value));
        }
        // Ids are unique across the whole scene, whatever the tags (a
        // `<ref>` names one, it defines none), as Mitsuba requires.
        let tag = node.tag_name().name();
        if let Some((_, id)) = attrs.iter().find(|(k, _)| k == "id")
            && tag != "ref"
        {
            let line = (self.line)(node);
            if let Some((first, at)) = self.ids.insert(id.clone(), (tag.to_owned(), line)) {
                let msg = format!(
                    "duplicate id \"{id}\": the <{first}> at line {at} has it (Mitsuba \
                     requires ids unique across the scene)"
                );
                return Err(FieldError::new(self.file, format!("{path}.id"), msg)
                    .at_line(line)
                    .into());
            }
        }
        self.spans.push((path.clone(), node.range()));
        let mut counts: HashMap<&str, usize> = HashMap::new();
        let mut children = Vec::new();
        for child in node
            .children()
            .filter(|n| n.is_element() && !n.has_tag_name("default"))
        {
            let tag = child.tag_name().name();
            let n = counts.entry(tag).or_default();
            let segment = match (child.attribute("name"), child.attribute("id")) {
                _ if PLUGINS.contains(&tag) => match child.attribute("id") {
                    Some(id) => format!("{tag}[{id}]"),
                    None => format!("{tag}[{n}]"),
                },
                (Some(name), _) => name.to_owned(),
                _ => tag.to_owned(),
            };
            *n += 1;
            children.push(self.element(child, format!("{path}.{segment}"), depth + 1)?);
        }
        Ok(Element {
            tag: node.tag_name().name().to_owned(),
            path,
            attrs,
            children,
            used: Cell::new(false),
        })
    }
}

/// Tags of plugin elements (named by `id` or position in paths).
pub const PLUGINS: [&str; 11] = [
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "texture",
    "rfilter",
    "medium",
    "phase",
];

/// `value` with every `$name` replaced by its `<default>`.
fn substitute(value: &str, defaults: &HashMap<String, String>) -> Result<String, String> {
    let mut out = String::with_capacity(value.len());
    let mut rest = value;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let len = after
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        let name = &after[..len];
        let v = defaults
            .get(name)
            .ok_or_else(|| format!("undefined parameter ${name} (no <default name=\"{name}\">)"))?;
        out.push_str(v);
        rest = &after[len..];
    }
    out.push_str(rest);
    Ok(out)
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// The plugin type (`type` attribute), or an error naming it as required.
    pub fn kind(&self, ctx: &Fields) -> Result<&str> {
        self.attr("type")
            .ok_or_else(|| ctx.err(&format!("{}.type", self.path), "missing type attribute"))
    }

    /// The child property called `name`, marked as read.
    pub fn prop(&self, name: &str) -> Option<&Element> {
        let found = self.children.iter().find(|c| c.attr("name") == Some(name));
        found.inspect(|c| c.used.set(true))
    }

    /// The children with tag `tag`, marked as read.
    pub fn tagged<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children
            .iter()
            .filter(move |c| c.tag == tag)
            .inspect(|c| c.used.set(true))
    }
}

/// Rejects the children of `el` that nobody read: an error for a second
/// property of a name already read (Mitsuba rejects it too), a warning for
/// names in `skippable` (documented as safe to skip), an error naming the
/// element and line for anything else.
pub(crate) fn finish(
    el: &Element,
    ctx: &Fields,
    skippable: &[&str],
    warnings: &mut Vec<FieldError>,
) -> Result<()> {
    for c in el.children.iter().filter(|c| !c.used.get()) {
        let name = c.attr("name").unwrap_or(&c.tag);
        let what = format!("<{} name=\"{name}\">", c.tag);
        let read_before = |o: &Element| o.used.get() && o.attr("name") == c.attr("name");
        if c.attr("name").is_some() && el.children.iter().any(read_before) {
            return Err(ctx.err(&c.path, format!("{what} is given more than once")));
        }
        if skippable.contains(&name) {
            warnings.push(ctx.located(
                &c.path,
                format!("{what} is skipped (no effect on this renderer)"),
            ));
        } else {
            return Err(ctx.err(
                &c.path,
                format!(
                    "unsupported {what} in <{} type=\"{}\">",
                    el.tag,
                    el.attr("type").unwrap_or_default()
                ),
            ));
        }
    }
    Ok(())
}
