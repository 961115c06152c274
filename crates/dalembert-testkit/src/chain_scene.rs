//! A planar chain as a scene file (the format of `docs/scenes.md`), for tests and benchmarks
//! that load it through the facade's reader.

/// A horizontal chain of `n` uniform rods (1 kg, 1 m) named `link0` …, pinned end to end and the
/// first to the ground at the origin by revolute joints `J0` …, with pin friction
/// `friction = (μ, r)` in every joint or none. Bodies and joints only: the caller adds
/// `[simulation]` and any `[initial]`.
pub fn planar_chain_toml(n: usize, friction: Option<(f64, f64)>) -> String {
    let mut text = String::from("[scene]\ngravity = [0.0, -9.81]\n");
    for k in 0..n {
        text += &format!(
            "[[bodies]]\nname = \"link{k}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [{}, 0.0]\n",
            k as f64 + 0.5
        );
    }
    for k in 0..n {
        let first = if k == 0 {
            "ground".into()
        } else {
            format!("link{}", k - 1)
        };
        text += &format!(
            "[[joints]]\nname = \"J{k}\"\ntype = \"revolute\"\nbodies = [\"{first}\", \"link{k}\"]\nat = [{k}.0, 0.0]\n"
        );
        if let Some((mu, r)) = friction {
            text += &format!("friction = {{ coefficient = {mu}, radius = {r} }}\n");
        }
    }
    text
}
