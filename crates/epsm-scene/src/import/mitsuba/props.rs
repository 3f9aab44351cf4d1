//! Typed readers of Mitsuba properties, each checking the tag and the
//! value and marking the property as read (see `parse::finish`).
//!
//! | reader | accepted elements | value |
//! |---|---|---|
//! | `float` | `<float>`, `<integer>` | one finite number |
//! | `integer` | `<integer>` | an `i64` |
//! | `boolean` | `<boolean>` | `true` / `false` |
//! | `string` | `<string>` | text |
//! | `rgb` | `<rgb>` (1 or 3 values), `<spectrum>`, `<float>` (1 value) | linear RGB |
//! | `point` | `<point>`, `<vector>` | `value="x, y, z"` or `x`, `y`, `z` attributes |
//!
//! Lists separate numbers by commas or white space; `nan` and `inf` are
//! errors naming the attribute.
//!
//! ```xml
//! <rgb name="reflectance" value="0.2, 0.4, 0.6"/>
//! ```

use glam::DVec3;

use super::parse::Element;
use crate::error::{FieldError, Result};
use crate::fields::Fields;

impl Element {
    /// Attribute `key` parsed as a list of finite numbers (comma or space separated).
    pub fn numbers(&self, ctx: &Fields, key: &str) -> Result<Option<Vec<f64>>> {
        let Some(text) = self.attr(key) else {
            return Ok(None);
        };
        let field = format!("{}.{key}", self.path);
        let parse = |s: &str| {
            let v = s
                .parse::<f64>()
                .map_err(|_| ctx.located(&field, format!("expected a number, found \"{s}\"")))?;
            ctx.finite(&field, v)
        };
        let words = text
            .split([',', ' ', '\t', '\n', '\r'])
            .filter(|s| !s.is_empty());
        Ok(Some(words.map(parse).collect::<Result<_, FieldError>>()?))
    }

    /// The property `name`, checking its tag is one of `tags`.
    fn typed(&self, ctx: &Fields, name: &str, tags: &[&str]) -> Result<Option<&Element>> {
        match self.prop(name) {
            Some(p) if !tags.contains(&p.tag.as_str()) => {
                let msg = format!("expected <{}>, found <{}>", tags.join("> or <"), p.tag);
                Err(ctx.err(&p.path, msg))
            }
            found => Ok(found),
        }
    }

    /// The `value` attribute of a property, required.
    fn value<'a>(&'a self, ctx: &Fields) -> Result<&'a str> {
        self.attr("value")
            .ok_or_else(|| ctx.err(&format!("{}.value", self.path), "missing value attribute"))
    }

    /// `<float name=…>` (an `<integer>` is accepted too), finite.
    pub fn float(&self, ctx: &Fields, name: &str) -> Result<Option<f64>> {
        let Some(p) = self.typed(ctx, name, &["float", "integer"])? else {
            return Ok(None);
        };
        p.value(ctx)?;
        match p.numbers(ctx, "value")?.as_deref() {
            Some(&[v]) => Ok(Some(v)),
            _ => Err(ctx.err(&format!("{}.value", p.path), "expected one number")),
        }
    }

    /// `<integer name=…>`.
    pub fn integer(&self, ctx: &Fields, name: &str) -> Result<Option<i64>> {
        let Some(p) = self.typed(ctx, name, &["integer"])? else {
            return Ok(None);
        };
        let v = p.value(ctx)?;
        let field = format!("{}.value", p.path);
        v.trim()
            .parse()
            .map(Some)
            .map_err(|_| ctx.err(&field, format!("expected an integer, found \"{v}\"")))
    }

    /// `<boolean name=…>` (`true` or `false`).
    pub fn boolean(&self, ctx: &Fields, name: &str) -> Result<Option<bool>> {
        let Some(p) = self.typed(ctx, name, &["boolean"])? else {
            return Ok(None);
        };
        match p.value(ctx)? {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            v => Err(ctx.err(
                &format!("{}.value", p.path),
                format!("expected true or false, found \"{v}\""),
            )),
        }
    }

    /// `<string name=…>`.
    pub fn string(&self, ctx: &Fields, name: &str) -> Result<Option<&str>> {
        match self.typed(ctx, name, &["string"])? {
            Some(p) => p.value(ctx).map(Some),
            None => Ok(None),
        }
    }

    /// `<rgb name=…>` (three values, or one for grey) or a uniform
    /// `<spectrum name=… value="v"/>`.
    pub fn rgb(&self, ctx: &Fields, name: &str) -> Result<Option<[f64; 3]>> {
        let Some(p) = self.typed(ctx, name, &["rgb", "spectrum", "float"])? else {
            return Ok(None);
        };
        p.value(ctx)?;
        match p.numbers(ctx, "value")?.as_deref() {
            Some(&[v]) => Ok(Some([v; 3])),
            Some(&[r, g, b]) if p.tag == "rgb" => Ok(Some([r, g, b])),
            _ => Err(ctx.err(
                &format!("{}.value", p.path),
                "expected one value, or three for <rgb>",
            )),
        }
    }

    /// `<point name=…>` or `<vector name=…>` (`value="x, y, z"` or `x`/`y`/`z` attributes).
    pub fn point(&self, ctx: &Fields, name: &str) -> Result<Option<DVec3>> {
        match self.typed(ctx, name, &["point", "vector"])? {
            Some(p) => p.xyz(ctx, 0.0).map(Some),
            None => Ok(None),
        }
    }

    /// This element's vector: its `value` list, or its `x`, `y`, `z`
    /// attributes (each `default` when absent).
    pub fn xyz(&self, ctx: &Fields, default: f64) -> Result<DVec3> {
        if let Some(v) = self.numbers(ctx, "value")? {
            return match *v.as_slice() {
                [s] => Ok(DVec3::splat(s)),
                [x, y, z] => Ok(DVec3::new(x, y, z)),
                _ => Err(ctx.err(&format!("{}.value", self.path), "expected 1 or 3 numbers")),
            };
        }
        let mut out = [default; 3];
        for (o, key) in out.iter_mut().zip(["x", "y", "z"]) {
            if let Some(v) = self.numbers(ctx, key)? {
                *o = *v.first().filter(|_| v.len() == 1).ok_or_else(|| {
                    ctx.err(&format!("{}.{key}", self.path), "expected one number")
                })?;
            }
        }
        Ok(DVec3::from_array(out))
    }
}
