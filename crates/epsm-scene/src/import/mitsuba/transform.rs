//! `<transform name="to_world">`: its children are applied in document
//! order, each one left-multiplied onto the product so far (Mitsuba 3's rule):
//! `to_world = op[n−1] · … · op[0]`.
//!
//! | child | attributes | meaning |
//! |---|---|---|
//! | `translate` | `value="x, y, z"` or `x`, `y`, `z` (default 0) | translation |
//! | `rotate` | axis as `value` or `x`, `y`, `z`; `angle` (degrees) | right-handed rotation about the axis |
//! | `scale` | `value` (one number: uniform, or three) or `x`, `y`, `z` (default 1) | scale |
//! | `matrix` | `value` = 16 numbers, row-major, last row `0 0 0 1` | affine matrix |
//! | `lookat` | `origin`, `target`, `up` (each `"x, y, z"`) | columns `(left, up′, dir, origin)`, `left = up × dir` |
//!
//! ```xml
//! <transform name="to_world">
//!     <scale value="0.5"/>
//!     <rotate x="1" angle="-90"/>
//!     <translate x="0" y="1" z="0"/>
//! </transform>
//! ```

use glam::{DAffine3, DMat3, DMat4, DVec3};

use super::parse::Element;
use crate::error::Result;
use crate::fields::Fields;

/// The affine map of a `<transform>` element; errors name the child and line.
pub(crate) fn transform(el: &Element, ctx: &Fields) -> Result<DAffine3> {
    if el.tag != "transform" {
        return Err(ctx.err(
            &el.path,
            format!("expected <transform>, found <{}>", el.tag),
        ));
    }
    let mut m = DAffine3::IDENTITY;
    for op in &el.children {
        let field = |key: &str| format!("{}.{key}", op.path);
        let step = match op.tag.as_str() {
            "translate" => DAffine3::from_translation(op.xyz(ctx, 0.0)?),
            "scale" => DAffine3::from_scale(op.xyz(ctx, 1.0)?),
            "rotate" => {
                let axis = op
                    .xyz(ctx, 0.0)?
                    .try_normalize()
                    .ok_or_else(|| ctx.err(&op.path, "expected a non-zero rotation axis"))?;
                let angle = match op.numbers(ctx, "angle")?.as_deref() {
                    Some(&[a]) => a,
                    _ => return Err(ctx.err(&field("angle"), "expected one angle in degrees")),
                };
                DAffine3::from_axis_angle(axis, angle.to_radians())
            }
            "matrix" => matrix(op, ctx)?,
            "lookat" => look_at(op, ctx)?,
            other => {
                return Err(ctx.err(
                    &op.path,
                    format!("unsupported transform operation <{other}>"),
                ));
            }
        };
        m = step * m;
    }
    if !m.is_finite() || m.matrix3.determinant().abs() < 1e-12 {
        return Err(ctx.err(&el.path, "the transform is singular or not finite"));
    }
    Ok(m)
}

/// `<matrix value="…16 numbers, row-major…"/>`.
fn matrix(op: &Element, ctx: &Fields) -> Result<DAffine3> {
    let field = format!("{}.value", op.path);
    let values = op.numbers(ctx, "value")?.unwrap_or_default();
    let Ok(rows) = <[f64; 16]>::try_from(values.as_slice()) else {
        return Err(ctx.err(
            &field,
            format!("expected 16 numbers, found {}", values.len()),
        ));
    };
    let m = DMat4::from_cols_array(&rows).transpose();
    if m.row(3) != glam::DVec4::W {
        return Err(ctx.err(&field, "expected an affine matrix (last row 0 0 0 1)"));
    }
    Ok(DAffine3::from_mat4(m))
}

/// `<lookat origin=… target=… up=…/>`.
fn look_at(op: &Element, ctx: &Fields) -> Result<DAffine3> {
    let vec = |key: &str| -> Result<DVec3> {
        let field = format!("{}.{key}", op.path);
        match op.numbers(ctx, key)?.as_deref() {
            Some(&[x, y, z]) => Ok(DVec3::new(x, y, z)),
            _ => Err(ctx.err(&field, "expected \"x, y, z\"")),
        }
    };
    let (origin, target, up) = (vec("origin")?, vec("target")?, vec("up")?);
    let dir = (target - origin).try_normalize().ok_or_else(|| {
        ctx.err(
            &format!("{}.target", op.path),
            "equals origin: the view direction is undefined",
        )
    })?;
    let left = up.cross(dir).try_normalize().ok_or_else(|| {
        ctx.err(
            &format!("{}.up", op.path),
            "is zero or parallel to the view direction",
        )
    })?;
    let new_up = dir.cross(left);
    Ok(DAffine3::from_mat3_translation(
        DMat3::from_cols(left, new_up, dir),
        origin,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::mitsuba::parse::parse;
    use std::path::Path;

    /// The `to_world` of the first shape of a scene whose transform body is `body`.
    fn to_world(body: &str) -> Result<DAffine3> {
        let text = format!(
            "<scene version=\"3.0.0\"><shape type=\"cube\"><transform name=\"to_world\">{body}</transform></shape></scene>"
        );
        let file = Path::new("t.xml");
        let doc = parse(&text, file)?;
        let ctx = Fields {
            file,
            base: Default::default(),
            locator: &doc.locator,
            prefix: "",
        };
        transform(&doc.root.children[0].children[0], &ctx)
    }

    #[test]
    fn operations_compose_left_to_right_in_document_order() {
        let m = to_world(r#"<scale value="2"/><rotate y="1" angle="90"/><translate x="1"/>"#)
            .expect("valid");
        // (1, 0, 0) → scaled (2, 0, 0) → rotated about +y to (0, 0, −2) → translated (1, 0, −2).
        assert!(
            m.transform_point3(DVec3::X)
                .abs_diff_eq(DVec3::new(1.0, 0.0, -2.0), 1e-12)
        );
        let row_major =
            to_world(r#"<matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>"#).expect("valid");
        assert_eq!(row_major.translation, DVec3::new(5.0, 6.0, 7.0));
    }

    #[test]
    fn look_at_maps_plus_z_to_the_view_direction_and_plus_x_to_the_left() {
        let m =
            to_world(r#"<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>"#).expect("valid");
        assert!(
            m.transform_vector3(DVec3::Z)
                .abs_diff_eq(DVec3::NEG_Z, 1e-12)
        );
        assert!(
            m.transform_vector3(DVec3::X)
                .abs_diff_eq(DVec3::NEG_X, 1e-12),
            "left of a camera looking down −z is −x"
        );
        assert_eq!(m.translation, DVec3::new(0.0, 0.0, 5.0));
    }

    #[test]
    fn bad_operations_are_located_errors() {
        for (body, expect) in [
            (r#"<scale value="0"/>"#, "singular"),
            (r#"<rotate angle="10"/>"#, "non-zero rotation axis"),
            (r#"<matrix value="1 2 3"/>"#, "16 numbers"),
            (r#"<translate x="nan"/>"#, "finite"),
            (
                r#"<lookat origin="0,0,0" target="0,0,0" up="0,1,0"/>"#,
                "undefined",
            ),
            (r#"<shear value="1"/>"#, "<shear>"),
        ] {
            let msg = to_world(body).expect_err(body).to_string();
            assert!(
                msg.contains(expect) && msg.contains("t.xml:1"),
                "{body}: {msg}"
            );
        }
    }
}
