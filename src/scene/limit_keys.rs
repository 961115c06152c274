//! The `limits`, `restitution` and `rest_speed` keys of a joint, read alike for planar and
//! spatial scenes (`docs/limits.md`).

use super::error::SceneError;
use super::names::Ctx;
use dalembert_system::{JointLimit, REST_SPEED};
use std::ops::Range;
use toml::Spanned;

/// A joint's limit keys as the file gives them.
pub(crate) struct LimitKeys<'a> {
    /// `limits = [lower, upper]`.
    pub limits: Option<&'a Spanned<Vec<f64>>>,
    /// `restitution = e` (default 0).
    pub restitution: Option<&'a Spanned<f64>>,
    /// `rest_speed` (default [`REST_SPEED`]).
    pub rest_speed: Option<&'a Spanned<f64>>,
}

/// The limit of joint `name`, with the span of its `limits` key; `None` without `limits`
/// (`restitution` or `rest_speed` alone are refused). The bounds and coefficients are checked
/// ([`JointLimit::check`]); each error is placed at the key at fault and names the joint.
pub(crate) fn limit_keys(
    ctx: &Ctx<'_>,
    name: &str,
    keys: LimitKeys<'_>,
) -> Result<Option<(JointLimit, Range<usize>)>, SceneError> {
    let owner = format!("joint '{name}'");
    let Some(bounds) = keys.limits else {
        let stray = [("restitution", keys.restitution), ("rest_speed", keys.rest_speed)];
        if let Some((key, value)) = stray.into_iter().find_map(|(k, v)| v.map(|v| (k, v))) {
            return Err(ctx.err(
                Some(value.span()),
                format!("{owner}: '{key}' belongs to a joint with 'limits = [lower, upper]'"),
            ));
        }
        return Ok(None);
    };
    let &[lower, upper] = bounds.get_ref().as_slice() else {
        return Err(ctx.err(
            Some(bounds.span()),
            format!(
                "{owner}: limits must be [lower, upper], got {} values",
                bounds.get_ref().len()
            ),
        ));
    };
    let limit = JointLimit {
        element: "joint",
        name: name.to_string(),
        lower,
        upper,
        restitution: keys.restitution.map_or(0.0, |r| *r.get_ref()),
        rest_speed: keys.rest_speed.map_or(REST_SPEED, |r| *r.get_ref()),
        within_turn: false,
    };
    if let Err(what) = limit.check() {
        let at = if what.contains("restitution") {
            keys.restitution.map(|r| r.span())
        } else if what.contains("rest_speed") {
            keys.rest_speed.map(|r| r.span())
        } else {
            None
        };
        return Err(ctx.err(at.or(Some(bounds.span())), format!("{owner}: {what}")));
    }
    Ok(Some((limit, bounds.span())))
}
