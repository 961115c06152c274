//! Changing values of a scene by path (`bodies.slider.mass`, `forces.return-spring.stiffness`,
//! `simulation.end`, `scene.gravity`): the scene is rebuilt from its edited TOML, so every rule of
//! the format applies to the new value exactly as if it had been written in the file.

use super::{Scene, SceneError};
use toml::{Table, Value};

/// A value for [`Scene::with_values`]: what a scene file can hold at a key.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SceneValue {
    /// A number.
    Number(f64),
    /// An integer (written as such, e.g. for counts).
    Integer(i64),
    /// A name, such as `"rk4"`.
    Text(String),
    /// A flag.
    Flag(bool),
    /// A list, such as a point `[x, y]`.
    List(Vec<SceneValue>),
}

impl SceneValue {
    /// Reads a value written as on the command line (`2`, `1.5e3`, `[0, -9.81]`, `rk4`): a TOML
    /// value when it is one, otherwise the text itself.
    pub fn parse(text: &str) -> SceneValue {
        let parsed = toml::from_str::<Table>(&format!("v = {text}"))
            .ok()
            .and_then(|t| t.get("v").cloned())
            .and_then(|v| from_toml(&v));
        parsed.unwrap_or_else(|| SceneValue::Text(text.to_string()))
    }

    fn to_toml(&self) -> Value {
        match self {
            SceneValue::Number(x) => Value::Float(*x),
            SceneValue::Integer(i) => Value::Integer(*i),
            SceneValue::Text(s) => Value::String(s.clone()),
            SceneValue::Flag(b) => Value::Boolean(*b),
            SceneValue::List(l) => Value::Array(l.iter().map(SceneValue::to_toml).collect()),
        }
    }
}

fn from_toml(v: &Value) -> Option<SceneValue> {
    Some(match v {
        Value::Float(x) => SceneValue::Number(*x),
        Value::Integer(i) => SceneValue::Integer(*i),
        Value::String(s) => SceneValue::Text(s.clone()),
        Value::Boolean(b) => SceneValue::Flag(*b),
        Value::Array(a) => SceneValue::List(a.iter().map(from_toml).collect::<Option<_>>()?),
        _ => return None,
    })
}

impl std::fmt::Display for SceneValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.to_toml())
    }
}

impl From<f64> for SceneValue {
    fn from(x: f64) -> Self {
        SceneValue::Number(x)
    }
}

impl From<&str> for SceneValue {
    fn from(s: &str) -> Self {
        SceneValue::Text(s.to_string())
    }
}

/// The arrays of named tables in a scene file, with the word for one element.
const NAMED: &[(&str, &str)] = &[
    ("bodies", "body"),
    ("joints", "joint"),
    ("drivers", "driver"),
    ("forces", "force"),
    ("couplings", "coupling"),
];

/// The tables of a scene file.
const TABLES: &[&str] = &["scene", "simulation"];

impl Scene {
    /// The scene with each `(path, value)` set, rebuilt and re-assembled. A path names a table and a
    /// key (`simulation.end`, `scene.gravity`) or an element by name and its key
    /// (`bodies.slider.mass`, `forces.return-spring.stiffness`, `bodies.crank.shape.rod`); keys
    /// not yet in the file are added. Errors are one line: an unknown table or element (with the
    /// names that exist), or the new value breaking a rule of the format.
    ///
    /// ```
    /// # fn main() -> Result<(), dalembert::SceneError> {
    /// let scene = dalembert::Scene::from_path("scenes/slider-crank.toml")?;
    /// let heavier = scene.with_values(&[("bodies.slider.mass", 2.0.into())])?;
    /// assert_eq!(heavier.model.planar().unwrap().bodies()[2].mass, 2.0);
    /// # Ok(()) }
    /// ```
    pub fn with_values(&self, values: &[(&str, SceneValue)]) -> Result<Scene, SceneError> {
        let fail = |message: String| SceneError {
            file: self.origin.clone(),
            position: None,
            message,
        };
        let mut file: Table = toml::from_str(&self.source).map_err(|e| fail(e.message().to_string()))?;
        for (path, value) in values {
            let (slot, _) = locate(&mut file, path).map_err(|m| fail(format!("cannot set '{path}': {m}")))?;
            *slot = value.to_toml();
        }
        let text = toml::to_string(&file).map_err(|e| fail(e.to_string()))?;
        let what: Vec<String> = values.iter().map(|(p, v)| format!("{p} = {v}")).collect();
        Scene::from_toml(&text, &self.origin).map_err(|e| {
            fail(format!(
                "with {}: {}",
                what.join(", "),
                // The position refers to the regenerated text: the message is what matters.
                e.message
            ))
        })
    }
}

impl Scene {
    /// The scene started at rest at `equilibrium` ([`Scene::equilibrium`]): its text with an
    /// `[initial]` table giving every position column's value there and every velocity 0 (any
    /// `[initial]` the scene had is replaced), read again. Its `source` is what `dalembert
    /// equilibrium --output` writes.
    pub fn resting_at(&self, equilibrium: &crate::Equilibrium) -> Result<Scene, SceneError> {
        let fail = |message: String| SceneError {
            file: self.origin.clone(),
            position: None,
            message,
        };
        let mut file: Table = toml::from_str(&self.source).map_err(|e| fail(e.message().to_string()))?;
        let rows = crate::output::Rows::new(&self.model);
        let (_, v_columns) = rows.state_columns(&self.model);
        let positions: Table = (equilibrium.positions.iter())
            .map(|(name, v)| (name.clone(), toml::Value::Float(*v)))
            .collect();
        let velocities: Table = (v_columns.iter())
            .map(|&k| (rows.names()[k].clone(), toml::Value::Float(0.0)))
            .collect();
        let mut initial = Table::new();
        initial.insert("positions".into(), toml::Value::Table(positions));
        initial.insert("velocities".into(), toml::Value::Table(velocities));
        file.insert("initial".into(), toml::Value::Table(initial));
        let text = toml::to_string(&file).map_err(|e| fail(e.to_string()))?;
        Scene::from_toml(&text, &self.origin).map_err(|e| fail(format!("at rest at the equilibrium: {}", e.message)))
    }
}

impl Scene {
    /// `Ok` when `path` names a place [`Scene::with_values`] can set: an existing table or a named
    /// element, and a key the format has there (checked by reading the scene with the key added,
    /// so the format's own list of keys decides). The error is one line naming the path and the
    /// nearest valid key. The value's own rules are checked when it is set.
    pub fn check_path(&self, path: &str) -> Result<(), SceneError> {
        let fail = |message: String| SceneError {
            file: self.origin.clone(),
            position: None,
            message,
        };
        let mut file: Table = toml::from_str(&self.source).map_err(|e| fail(e.message().to_string()))?;
        let added = {
            let (_, added) = locate(&mut file, path).map_err(|m| fail(format!("cannot set '{path}': {m}")))?;
            added
        };
        if !added {
            return Ok(());
        }
        // A key the file does not hold yet: the format refuses it if it has no such key.
        let key = path.rsplit('.').next().unwrap_or(path);
        let Ok(text) = toml::to_string(&file) else {
            return Ok(());
        };
        let Err(e) = Scene::from_toml(&text, &self.origin) else {
            return Ok(());
        };
        let Some(expected) = e.message.strip_prefix(&format!("unknown field `{key}`")) else {
            return Ok(());
        };
        let keys: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
        let place = &path[..path.len() - key.len() - 1];
        let hint = super::nearest(key, &keys).map_or(String::new(), |k| format!("; did you mean '{place}.{k}'?"));
        Err(fail(format!(
            "cannot set '{path}': {place} has no key '{key}' (its keys: {}){hint}",
            keys.join(", ")
        )))
    }
}

/// The value at `path` in the scene file `source` (`None` when the file does not write it).
pub(crate) fn value_at(source: &str, path: &str) -> Result<Option<SceneValue>, String> {
    let mut file: Table = toml::from_str(source).map_err(|e| e.message().to_string())?;
    let (slot, added) = locate(&mut file, path).map_err(|m| format!("cannot read '{path}': {m}"))?;
    Ok(if added { None } else { from_toml(slot) })
}

/// The slot for `path` in a scene file's table, created when the key is new (then `true`).
fn locate<'a>(file: &'a mut Table, path: &str) -> Result<(&'a mut Value, bool), String> {
    let (head, rest) = path
        .split_once('.')
        .ok_or("a path is a table and a key, e.g. bodies.slider.mass")?;
    if TABLES.contains(&head) {
        let table = file
            .entry(head)
            .or_insert_with(|| Value::Table(Table::new()))
            .as_table_mut()
            .ok_or(format!("[{head}] is not a table"))?;
        return key_slot(table, rest);
    }
    let Some(&(_, one)) = NAMED.iter().find(|(h, _)| *h == head) else {
        let known: Vec<&str> = TABLES.iter().chain(NAMED.iter().map(|(h, _)| h)).copied().collect();
        return Err(format!("unknown table '{head}' (expected {})", known.join(", ")));
    };
    let Some(elements) = file.get_mut(head).and_then(Value::as_array_mut) else {
        return Err(format!("the scene has no {head}"));
    };
    let names: Vec<String> = elements
        .iter()
        .filter_map(|e| e.get("name").and_then(Value::as_str).map(str::to_string))
        .collect();
    // The longest name that the rest of the path starts with (names may contain dots).
    let found = elements
        .iter()
        .enumerate()
        .filter_map(|(k, e)| {
            let name = e.get("name")?.as_str()?;
            let after = rest.strip_prefix(name)?;
            (after.len() > 1 && after.starts_with('.')).then_some((k, name.len()))
        })
        .max_by_key(|&(_, len)| len);
    let Some((k, len)) = found else {
        return Err(format!(
            "no {one} named '{}' (the scene's {head}: {})",
            rest.split('.').next().unwrap_or(rest),
            names.join(", ")
        ));
    };
    let table = elements[k].as_table_mut().ok_or(format!("{one} {k} is not a table"))?;
    key_slot(table, &rest[len + 1..])
}

/// The slot for a dotted `key` inside `table` (`mass`, `shape.rod`), intermediate tables created;
/// `true` when the key is new.
fn key_slot<'a>(table: &'a mut Table, key: &str) -> Result<(&'a mut Value, bool), String> {
    if key.is_empty() {
        return Err("the path names no key".into());
    }
    match key.split_once('.') {
        None => {
            let added = !table.contains_key(key);
            Ok((table.entry(key).or_insert(Value::Boolean(false)), added))
        }
        Some((first, more)) => {
            let inner = table
                .entry(first)
                .or_insert_with(|| Value::Table(Table::new()))
                .as_table_mut()
                .ok_or(format!("'{first}' holds a value, not a table"))?;
            key_slot(inner, more)
        }
    }
}
