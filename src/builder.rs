//! Models written in code: [`ModelBuilder`] describes a scene element by element, with the keys and
//! defaults of scene files (`docs/scenes.md` lists them; each setter is named after its key, and
//! [`Element::set`] takes any key), and builds it through the scene reader, so that a model written in code is
//! checked, assembled and defaulted exactly as the same model in a file, and carries its TOML text
//! (sweeps and `with_values` work on it).
//!
//! A pendulum: a uniform rod of 1 m on a pin at the origin, released horizontal.
//!
//! ```
//! use dalembert::builder::{body, joint, ModelBuilder};
//! let scene = ModelBuilder::planar("pendulum")
//!     .gravity([0.0, -9.81])
//!     .body(body("rod").mass(1.0).rod(1.0).position([0.5, 0.0]))
//!     .joint(joint("pin", "revolute", ["ground", "rod"]).at([0.0, 0.0]))
//!     .simulation("end", 1.0)
//!     .build()?;
//! let mut sim = scene.simulator()?;
//! // A reaction by name: at release the rod's angular acceleration is 3g/(2L), its centre falls
//! // at 3g/4, and the pin carries the rest of its weight, m g / 4 (vertical; no horizontal part).
//! let (fx, fy) = (sim.value("pin.fx")?, sim.value("pin.fy")?);
//! assert!((fy.abs() - 9.81 / 4.0).abs() < 1e-9 && fx.abs() < 1e-12, "pin force ({fx}, {fy})");
//! sim.advance_to(1.0)?;
//! assert!(sim.value("rod.angle")? < 0.0, "it swings down");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A four-bar turned by a motor torque that is a named input, its crank read by name:
//!
//! ```
//! use dalembert::builder::{body, force, joint, Function, ModelBuilder};
//! let scene = ModelBuilder::planar("four-bar")
//!     .body(body("crank").mass(1.0).rod(1.0).position([0.0, 0.5]).angle(std::f64::consts::FRAC_PI_2))
//!     .body(body("coupler").mass(1.0).rod(2.0).position([1.0, 1.0]))
//!     .body(body("rocker").mass(1.0).rod(1.0).position([2.0, 0.5]).angle(std::f64::consts::FRAC_PI_2))
//!     .joint(joint("A", "revolute", ["ground", "crank"]).at([0.0, 0.0]))
//!     .joint(joint("B", "revolute", ["crank", "coupler"]).at([0.0, 1.0]))
//!     .joint(joint("C", "revolute", ["coupler", "rocker"]).at([2.0, 1.0]))
//!     .joint(joint("D", "revolute", ["rocker", "ground"]).at([2.0, 0.0]))
//!     .force(force("motor", "torque").set("joint", "A").set("value", Function::input("motor")))
//!     .simulation("integrator", "rk4")
//!     .build()?;
//! assert_eq!(scene.inputs, ["motor"]);
//! let mut sim = scene.simulator()?;
//! sim.set_input("motor", 1.0)?;
//! sim.advance_to(0.5)?;
//! // A parallelogram: the rocker turns with the crank.
//! let (crank, rocker) = (sim.value("crank.angle")?, sim.value("rocker.angle")?);
//! assert!((crank - rocker).abs() < 1e-8 && crank != std::f64::consts::FRAC_PI_2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A spatial body: a symmetric body hanging from a spherical joint and spinning about the
//! vertical (the keys of spatial scenes; three gravity components).
//!
//! ```
//! use dalembert::builder::{body, joint, ModelBuilder};
//! let scene = ModelBuilder::spatial("spinning bob")
//!     .gravity([0.0, 0.0, -9.81])
//!     .body(
//!         body("bob")
//!             .mass(2.0)
//!             .set("inertia", [0.02, 0.02, 0.01])
//!             .position([0.0, 0.0, -0.3])
//!             .set("angular_velocity", [0.0, 0.0, 50.0]),
//!     )
//!     .joint(joint("pivot", "spherical", ["ground", "bob"]).at([0.0, 0.0, 0.0]))
//!     .simulation("end", 1.0)
//!     .build()?;
//! let run = scene.record(&std::sync::atomic::AtomicBool::new(false));
//! assert!(run.outcome.is_ok());
//! // Gravity along the spin axis exerts no moment about the pivot: the spin stays 50 rad/s and
//! // the bob stays under the pivot, where the joint carries its weight.
//! let spin = run.table.column("bob.wz").unwrap();
//! assert!((spin.last().unwrap() - 50.0).abs() < 1e-9);
//! let fz = run.table.column("pivot.fz").unwrap();
//! assert!((fz.last().unwrap().abs() - 2.0 * 9.81).abs() < 1e-9);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{Scene, SceneError};
use toml::{Table, Value};

/// A value of a scene key: a number, a text, a point, a list of names, a function.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyValue(Value);

impl From<f64> for KeyValue {
    fn from(x: f64) -> Self {
        KeyValue(Value::Float(x))
    }
}

impl From<bool> for KeyValue {
    fn from(x: bool) -> Self {
        KeyValue(Value::Boolean(x))
    }
}

impl From<&str> for KeyValue {
    fn from(s: &str) -> Self {
        KeyValue(Value::String(s.to_string()))
    }
}

impl<const N: usize> From<[f64; N]> for KeyValue {
    fn from(xs: [f64; N]) -> Self {
        KeyValue(Value::Array(xs.iter().map(|&x| Value::Float(x)).collect()))
    }
}

impl<const N: usize, const M: usize> From<[[f64; N]; M]> for KeyValue {
    fn from(xs: [[f64; N]; M]) -> Self {
        KeyValue(Value::Array(xs.iter().map(|&p| KeyValue::from(p).0).collect()))
    }
}

impl<const N: usize> From<[&str; N]> for KeyValue {
    fn from(xs: [&str; N]) -> Self {
        KeyValue(Value::Array(xs.iter().map(|&x| Value::String(x.to_string())).collect()))
    }
}

impl From<Vec<KeyValue>> for KeyValue {
    /// An array of values, as `visual = [{ … }, { … }]` writes one.
    fn from(xs: Vec<KeyValue>) -> Self {
        KeyValue(Value::Array(xs.into_iter().map(|x| x.0).collect()))
    }
}

impl From<Function> for KeyValue {
    fn from(f: Function) -> Self {
        KeyValue(Value::Table(f.0))
    }
}

impl KeyValue {
    /// An inline table of keys, as `orientation = { quaternion = [1, 0, 0, 0] }` writes one.
    pub fn table<const N: usize>(entries: [(&str, KeyValue); N]) -> Self {
        KeyValue(Value::Table(
            entries.into_iter().map(|(k, v)| (k.to_string(), v.0)).collect(),
        ))
    }
}

/// A function of time as a scene writes it (`{ kind = "harmonic", … }`), or a named input.
#[derive(Debug, Clone, PartialEq)]
pub struct Function(Table);

impl Function {
    fn of(kind: &str, keys: &[(&str, f64)]) -> Self {
        let mut t = Table::new();
        t.insert("kind".into(), Value::String(kind.into()));
        for (k, v) in keys {
            t.insert((*k).into(), Value::Float(*v));
        }
        Function(t)
    }

    /// A named input, held at the value a simulator last set (0 before).
    pub fn input(name: &str) -> Self {
        let mut t = Table::new();
        t.insert("input".into(), Value::String(name.into()));
        Function(t)
    }

    /// This input times `gain` (`{ input = "NAME", gain = g }`).
    pub fn gain(mut self, gain: f64) -> Self {
        self.0.insert("gain".into(), Value::Float(gain));
        self
    }

    /// This input held within `[lo, hi]` (`{ input = "NAME", range = [lo, hi] }`).
    pub fn range(mut self, lo: f64, hi: f64) -> Self {
        self.0
            .insert("range".into(), Value::Array(vec![Value::Float(lo), Value::Float(hi)]));
        self
    }

    /// `value`, constant.
    pub fn constant(value: f64) -> Self {
        Function::of("constant", &[("value", value)])
    }

    /// `initial + rate · t` (for a driver: from its value in the model, at `rate`).
    pub fn linear(rate: f64) -> Self {
        Function::of("linear", &[("rate", rate)])
    }

    /// `amplitude · sin(2π frequency t)` (for a driver: about its value in the model).
    pub fn harmonic(amplitude: f64, frequency: f64) -> Self {
        Function::of("harmonic", &[("amplitude", amplitude), ("frequency", frequency)])
    }

    /// A quintic step to `to` between `t0` and `t1`.
    pub fn smooth_step(t0: f64, t1: f64, to: f64) -> Self {
        Function::of("smooth-step", &[("t0", t0), ("t1", t1), ("to", to)])
    }

    /// Any other key of the function table (`phase`, `offset`, `initial`, `absolute`, …).
    pub fn set(mut self, key: &str, value: impl Into<KeyValue>) -> Self {
        self.0.insert(key.into(), value.into().0);
        self
    }
}

/// One element of a model (a body, joint, driver or force): a table of scene keys.
#[derive(Debug, Clone, PartialEq)]
pub struct Element(Table);

/// A body named `name`: give its `mass`, inertia (`inertia`, `rod`, or `set("shape", …)`) and
/// `position` (approximate is fine: the model is assembled).
pub fn body(name: &str) -> Element {
    Element::named(name)
}

/// A joint named `name` of type `kind` (`revolute`, `prismatic`, …; spatial: `spherical`,
/// `universal`, …) between two bodies (`"ground"` is the ground).
pub fn joint(name: &str, kind: &str, bodies: [&str; 2]) -> Element {
    Element::named(name).set("type", kind).set("bodies", bodies)
}

/// A driver named `name` of type `kind` (`joint-angle`, `joint-displacement`, …): give its `joint`
/// (or body and coordinate) and `function`.
pub fn driver(name: &str, kind: &str) -> Element {
    Element::named(name).set("type", kind)
}

/// A force element named `name` of type `kind` (`force`, `torque`, `spring-damper`, …).
pub fn force(name: &str, kind: &str) -> Element {
    Element::named(name).set("type", kind)
}

/// A coupling named `name` of joint `follower`'s value to joint `leader`'s (spatial scenes):
/// give its `multiplier` and `offset`, or its `polynomial` (`docs/couplings.md`).
pub fn coupling(name: &str, leader: &str, follower: &str) -> Element {
    Element::named(name).set("leader", leader).set("follower", follower)
}

impl Element {
    /// The element without `key`.
    pub(crate) fn without(mut self, key: &str) -> Self {
        self.0.remove(key);
        self
    }

    fn named(name: &str) -> Self {
        let mut t = Table::new();
        t.insert("name".into(), Value::String(name.into()));
        Element(t)
    }

    /// Any key of the element, as a scene file writes it.
    pub fn set(mut self, key: &str, value: impl Into<KeyValue>) -> Self {
        self.0.insert(key.into(), value.into().0);
        self
    }

    /// `mass` (kg).
    pub fn mass(self, m: f64) -> Self {
        self.set("mass", m)
    }

    /// `inertia` about the centre of mass (kg m²; planar).
    pub fn inertia(self, j: f64) -> Self {
        self.set("inertia", j)
    }

    /// A uniform rod of length `l` (`shape = { rod = l }`: inertia m l²/12, drawn as a rod).
    pub fn rod(self, l: f64) -> Self {
        let mut t = Table::new();
        t.insert("rod".into(), Value::Float(l));
        let mut s = self;
        s.0.insert("shape".into(), Value::Table(t));
        s
    }

    /// `position` of the centre of mass (or of a joint's `at` point for joints: see
    /// [`Element::at`]).
    pub fn position(self, p: impl Into<KeyValue>) -> Self {
        self.set("position", p)
    }

    /// `angle` (rad; planar bodies).
    pub fn angle(self, a: f64) -> Self {
        self.set("angle", a)
    }

    /// `velocity` of the centre of mass.
    pub fn velocity(self, v: impl Into<KeyValue>) -> Self {
        self.set("velocity", v)
    }

    /// `at`: the joint's point (global, in the configuration written), or a force's.
    pub fn at(self, p: impl Into<KeyValue>) -> Self {
        self.set("at", p)
    }

    /// `axis` of a prismatic joint (or a spatial revolute one).
    pub fn axis(self, a: impl Into<KeyValue>) -> Self {
        self.set("axis", a)
    }
}

/// A model written in code (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelBuilder {
    name: String,
    file: Table,
}

impl ModelBuilder {
    fn new(name: &str) -> Self {
        let mut scene = Table::new();
        scene.insert("name".into(), Value::String(name.into()));
        let mut file = Table::new();
        file.insert("scene".into(), Value::Table(scene));
        ModelBuilder {
            name: name.into(),
            file,
        }
    }

    /// A planar model named `name` (no gravity until [`ModelBuilder::gravity`]).
    pub fn planar(name: &str) -> Self {
        ModelBuilder::new(name)
    }

    /// A spatial model named `name` (gravity 0 until [`ModelBuilder::gravity`]).
    pub fn spatial(name: &str) -> Self {
        let b = ModelBuilder::new(name);
        b.gravity([0.0, 0.0, 0.0])
    }

    /// `[scene] gravity`: two components (planar) or three (spatial).
    pub fn gravity(mut self, g: impl Into<KeyValue>) -> Self {
        if let Some(Value::Table(scene)) = self.file.get_mut("scene") {
            scene.insert("gravity".into(), g.into().0);
        }
        self
    }

    /// `[scene] KEY = value` (as `visual`, the ground's shapes in a spatial scene).
    pub fn scene(mut self, key: &str, value: impl Into<KeyValue>) -> Self {
        if let Some(Value::Table(scene)) = self.file.get_mut("scene") {
            scene.insert(key.into(), value.into().0);
        }
        self
    }

    fn push(mut self, list: &str, e: Element) -> Self {
        let entry = self
            .file
            .entry(list.to_string())
            .or_insert_with(|| Value::Array(Vec::new()));
        if let Value::Array(items) = entry {
            items.push(Value::Table(e.0));
        }
        self
    }

    /// Adds a body ([`body`]).
    pub fn body(self, b: Element) -> Self {
        self.push("bodies", b)
    }

    /// Adds a joint ([`joint`]).
    pub fn joint(self, j: Element) -> Self {
        self.push("joints", j)
    }

    /// Adds a driver ([`driver`]).
    pub fn driver(self, d: Element) -> Self {
        self.push("drivers", d)
    }

    /// Adds a force element ([`force`]).
    pub fn force(self, f: Element) -> Self {
        self.push("forces", f)
    }

    /// Adds a coupling between joint values ([`coupling`]; spatial scenes).
    pub fn coupling(self, c: Element) -> Self {
        self.push("couplings", c)
    }

    /// A `[simulation]` key: `end`, `formulation`, `integrator`, `step`, `output_every`,
    /// `stabilization`, a method's parameter, …
    pub fn simulation(mut self, key: &str, value: impl Into<KeyValue>) -> Self {
        let entry = self
            .file
            .entry("simulation".to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        if let Value::Table(t) = entry {
            t.insert(key.into(), value.into().0);
        }
        self
    }

    /// The model as a scene file's tables.
    pub(crate) fn into_table(self) -> Table {
        self.file
    }

    /// The model as a scene file's text.
    pub fn to_toml(&self) -> String {
        toml::to_string(&self.file).unwrap_or_default()
    }

    /// Builds, checks and assembles the model as the scene reader does a file. Errors name the
    /// element and key at fault (`model 'pendulum' (built in code): joint 'pin': unknown body
    /// 'rdo'`).
    pub fn build(&self) -> Result<Scene, SceneError> {
        let origin = format!("model '{}' (built in code)", self.name);
        Scene::from_toml(&self.to_toml(), &origin).map_err(|e| SceneError { position: None, ..e })
    }
}
