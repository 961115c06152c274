//! Strict readers for the scene's vectors and points: a wrong length, a non-number or a wrong shape
//! is an error that says what was expected (serde's fixed arrays silently drop extra elements, and
//! its untagged enums name internal types).

use super::format::FunctionDef;
use serde::de::{Deserializer, Error};
use serde::Deserialize;
use toml::Value;

/// A TOML number (integer or float) as `f64`.
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Integer(i) => Some(*i as f64),
        Value::Float(f) => Some(*f),
        _ => None,
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::String(s) => format!("the string \"{s}\""),
        Value::Array(a) => format!("an array of {}", a.len()),
        Value::Table(_) => "a table".into(),
        Value::Boolean(b) => format!("{b}"),
        Value::Datetime(d) => format!("the date {d}"),
        Value::Integer(_) | Value::Float(_) => "a number".into(),
    }
}

/// `[x, y]`: exactly two numbers; `what` says what was expected.
fn pair(v: &Value, what: &str) -> Result<[f64; 2], String> {
    match v {
        Value::Array(a) if a.len() == 2 => match (number(&a[0]), number(&a[1])) {
            (Some(x), Some(y)) => Ok([x, y]),
            _ => Err(format!(
                "expected {what}, found {} in it",
                describe(if number(&a[0]).is_none() { &a[0] } else { &a[1] })
            )),
        },
        Value::Array(a) if a.len() == 1 => Err(format!("expected {what}, got 1 element")),
        Value::Array(a) => Err(format!("expected {what}, got {} elements", a.len())),
        other => Err(format!("expected {what}, got {}", describe(other))),
    }
}

/// Deserializes `[x, y]`.
pub(crate) fn xy<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    pair(&Value::deserialize(d)?, "[x, y] (two numbers)").map_err(D::Error::custom)
}

/// Deserializes an optional `[x, y]`.
pub(crate) fn xy_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    xy(d).map(Some)
}

/// Deserializes an optional `[gx, gy]` gravity (a scene with `[gx, gy, gz]` is spatial and read by
/// the spatial format).
pub(crate) fn gravity_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    pair(&Value::deserialize(d)?, "[gx, gy] (planar) or [gx, gy, gz] (spatial)")
        .map(Some)
        .map_err(D::Error::custom)
}

/// Deserializes `[first, second]`: exactly two names.
pub(crate) fn two_names<'de, D: Deserializer<'de>>(d: D) -> Result<[String; 2], D::Error> {
    let v = Value::deserialize(d)?;
    const WHAT: &str = "two body names [\"first\", \"second\"]";
    match &v {
        Value::Array(a) if a.len() == 2 => match (&a[0], &a[1]) {
            (Value::String(x), Value::String(y)) => Ok([x.clone(), y.clone()]),
            (x, y) => Err(format!(
                "expected {WHAT}, found {} in it",
                describe(if matches!(x, Value::String(_)) { y } else { x })
            )),
        },
        Value::Array(a) => Err(format!("expected {WHAT}, got {} elements", a.len())),
        other => Err(format!("expected {WHAT}, got {}", describe(other))),
    }
    .map_err(D::Error::custom)
}

/// Deserializes an optional `[first, second]` pair of names.
pub(crate) fn two_names_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[String; 2]>, D::Error> {
    two_names(d).map(Some)
}

/// Deserializes an optional `[[x1, y1], [x2, y2]]`.
pub(crate) fn two_points_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[[f64; 2]; 2]>, D::Error> {
    two_points(&Value::deserialize(d)?).map(Some).map_err(D::Error::custom)
}

fn two_points(v: &Value) -> Result<[[f64; 2]; 2], String> {
    const WHAT: &str = "two points [[x1, y1], [x2, y2]]";
    match v {
        Value::Array(a) if a.len() == 2 => {
            let p = |k: usize| pair(&a[k], "each point as [x, y] (two numbers)").map_err(|e| format!("{WHAT}: {e}"));
            Ok([p(0)?, p(1)?])
        }
        other => Err(format!("expected {WHAT}, got {}", describe(other))),
    }
}

/// One global point, or two (for elements between two points).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Points {
    One([f64; 2]),
    Two([[f64; 2]; 2]),
}

impl<'de> Deserialize<'de> for Points {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let nested = matches!(&v, Value::Array(a) if a.first().is_some_and(|e| e.is_array()));
        if nested {
            two_points(&v).map(Points::Two)
        } else {
            pair(&v, "a point [x, y] or two points [[x1, y1], [x2, y2]]").map(Points::One)
        }
        .map_err(D::Error::custom)
    }
}

/// A number, a vector of `N` numbers (2 in planar scenes, 3 in spatial ones), or a time function.
#[derive(Debug, Clone)]
pub(crate) enum ValueDef<const N: usize = 2> {
    Number(f64),
    Vector([f64; N]),
    Function(Box<FunctionDef>),
}

impl<'de, const N: usize> Deserialize<'de> for ValueDef<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        if let Some(x) = number(&v) {
            return Ok(ValueDef::Number(x));
        }
        let (vector, count) = if N == 3 {
            ("[x, y, z]", "three")
        } else {
            ("[x, y]", "two")
        };
        match v {
            Value::Array(_) if N == 3 => three(&v)
                .map(|x| ValueDef::Vector(std::array::from_fn(|k| x[k])))
                .map_err(D::Error::custom),
            Value::Array(_) => numbers::<N>(&v, &format!("{vector} ({count} numbers)"))
                .map(ValueDef::Vector)
                .map_err(D::Error::custom),
            Value::Table(_) => v
                .try_into::<FunctionDef>()
                .map(|f| ValueDef::Function(Box::new(f)))
                .map_err(|e| D::Error::custom(format!("function table: {}", e.message().trim()))),
            other => Err(D::Error::custom(format!(
                "expected a number, {vector} or a function table {{ kind = ... }}, got {}",
                describe(&other)
            ))),
        }
    }
}

/// Exactly `N` numbers; `what` says what was expected.
fn numbers<const N: usize>(v: &Value, what: &str) -> Result<[f64; N], String> {
    match v {
        Value::Array(a) if a.len() == N => {
            let mut out = [0.0; N];
            for (o, e) in out.iter_mut().zip(a) {
                *o = number(e).ok_or_else(|| format!("expected {what}, found {} in it", describe(e)))?;
            }
            Ok(out)
        }
        Value::Array(a) if a.len() == 1 => Err(format!("expected {what}, got 1 element")),
        Value::Array(a) => Err(format!("expected {what}, got {} elements", a.len())),
        other => Err(format!("expected {what}, got {}", describe(other))),
    }
}

/// Deserializes `[x, y, z]` (a spatial scene's vector: two numbers get a reminder of why three
/// are expected).
pub(crate) fn xyz<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    three(&Value::deserialize(d)?).map_err(D::Error::custom)
}

/// `[x, y, z]`, with the reminder for two numbers.
fn three(v: &Value) -> Result<[f64; 3], String> {
    if matches!(v, Value::Array(a) if a.len() == 2) {
        return Err(
            "expected [x, y, z] (three numbers): the scene is spatial because its gravity has three components, got 2 elements"
                .into(),
        );
    }
    numbers(v, "[x, y, z] (three numbers)")
}

/// Deserializes an optional `[x, y, z]`.
pub(crate) fn xyz_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    xyz(d).map(Some)
}

/// Deserializes an optional quaternion `[e0, e1, e2, e3]`.
pub(crate) fn quaternion_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 4]>, D::Error> {
    numbers(
        &Value::deserialize(d)?,
        "[e0, e1, e2, e3] (four numbers, e0 the scalar part)",
    )
    .map(Some)
    .map_err(D::Error::custom)
}

/// Deserializes an optional pair of axes `[[x1, y1, z1], [x2, y2, z2]]`.
pub(crate) fn two_axes_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[[f64; 3]; 2]>, D::Error> {
    two_xyz(&Value::deserialize(d)?, "two axes [[x1, y1, z1], [x2, y2, z2]]")
        .map(Some)
        .map_err(D::Error::custom)
}

/// Two segments in `N` dimensions, each by its two ends.
pub(crate) type TwoSegments<const N: usize = 3> = [[[f64; N]; 2]; 2];

/// Deserializes an optional pair of spatial segments
/// `[[[x, y, z], [x, y, z]], [[x, y, z], [x, y, z]]]` (each by its two ends).
pub(crate) fn two_segments_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<TwoSegments>, D::Error> {
    two_segments(
        &Value::deserialize(d)?,
        "two segments [[[x1, y1, z1], [x2, y2, z2]], [[x3, y3, z3], [x4, y4, z4]]] (each by its two ends)",
        "[x, y, z] (three numbers)",
    )
    .map(Some)
    .map_err(D::Error::custom)
}

/// Deserializes an optional pair of planar segments `[[[x, y], [x, y]], [[x, y], [x, y]]]`.
pub(crate) fn two_segments2_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<TwoSegments<2>>, D::Error> {
    two_segments(
        &Value::deserialize(d)?,
        "two segments [[[x1, y1], [x2, y2]], [[x3, y3], [x4, y4]]] (each by its two ends)",
        "[x, y] (two numbers)",
    )
    .map(Some)
    .map_err(D::Error::custom)
}

fn two_segments<const N: usize>(v: &Value, what: &str, point: &str) -> Result<TwoSegments<N>, String> {
    let Value::Array(a) = v else {
        return Err(format!("expected {what}, got {}", describe(v)));
    };
    let is_point = |p: &Value| matches!(p, Value::Array(e) if e.first().is_some_and(|x| !x.is_array()));
    if a.len() == 2 && a.iter().all(is_point) {
        return Err(format!("expected {what}, got one segment (two points)"));
    }
    if a.len() != 2 {
        return Err(format!("expected {what}, got an array of {}", a.len()));
    }
    let segment = |s: &Value| -> Result<[[f64; N]; 2], String> {
        match s {
            Value::Array(e) if e.len() == 2 => {
                let p = |k: usize| {
                    numbers::<N>(&e[k], &format!("each point as {point}")).map_err(|m| format!("{what}: {m}"))
                };
                Ok([p(0)?, p(1)?])
            }
            other => Err(format!("expected {what}, got {} for a segment", describe(other))),
        }
    };
    Ok([segment(&a[0])?, segment(&a[1])?])
}

fn two_xyz(v: &Value, what: &str) -> Result<[[f64; 3]; 2], String> {
    match v {
        Value::Array(a) if a.len() == 2 => {
            let p = |k: usize| numbers(&a[k], "each as [x, y, z] (three numbers)").map_err(|e| format!("{what}: {e}"));
            Ok([p(0)?, p(1)?])
        }
        other => Err(format!("expected {what}, got {}", describe(other))),
    }
}

/// One global point `[x, y, z]`, or two (for elements between two points).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Points3 {
    One([f64; 3]),
    Two([[f64; 3]; 2]),
}

impl<'de> Deserialize<'de> for Points3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let nested = matches!(&v, Value::Array(a) if a.first().is_some_and(|e| e.is_array()));
        if nested {
            two_xyz(&v, "two points [[x1, y1, z1], [x2, y2, z2]]").map(Points3::Two)
        } else {
            numbers(&v, "a point [x, y, z] or two points [[x1, y1, z1], [x2, y2, z2]]").map(Points3::One)
        }
        .map_err(D::Error::custom)
    }
}

/// A spatial body's inertia: three principal moments along the body axes, or the six components
/// `[Jxx, Jyy, Jzz, Jxy, Jxz, Jyz]` of the tensor in the body frame.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Inertia3 {
    Principal([f64; 3]),
    Tensor([f64; 6]),
}

impl<'de> Deserialize<'de> for Inertia3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        const WHAT: &str =
            "[Jx, Jy, Jz] (principal moments along the body axes) or [Jxx, Jyy, Jzz, Jxy, Jxz, Jyz] (tensor components)";
        match &v {
            Value::Array(a) if a.len() == 6 => numbers(&v, WHAT).map(Inertia3::Tensor),
            Value::Array(a) if a.len() == 3 => numbers(&v, WHAT).map(Inertia3::Principal),
            _ => numbers::<3>(&v, WHAT).map(Inertia3::Principal),
        }
        .map_err(D::Error::custom)
    }
}
