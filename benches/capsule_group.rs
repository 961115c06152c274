//! The cost of a capsule group's broad phase (issue #38: a chain of 64 links on a floor stays
//! linear in cost): the applied forces of a chain of `n` capsule links (0.1 m long, radius
//! 0.02 m, spherical joints) lying straight on a floor, its self-contact as one `capsule-group`
//! (sweep and prune) or as every pair of links that are not neighbours written out as
//! `capsule-capsule`, or none. One evaluation of the applied forces each (gravity, the floor's
//! contacts and the self-contact; no pair of links touches, so what is timed is finding that).
//! `cargo bench --bench capsule_group`; the figures are in `docs/contact.md`, "Groups and the
//! broad phase".

use criterion::{BenchmarkId, Criterion};
use dalembert::Scene;

/// The chain of `n` links with its self-contact as `mode`: "group", "pairs" or "none".
fn chain(n: usize, mode: &str) -> Scene {
    let (l, r) = (0.1, 0.02);
    let segment = |k: usize| {
        format!(
            "[[{:?}, 0.0, {r:?}], [{:?}, 0.0, {r:?}]]",
            k as f64 * l,
            (k + 1) as f64 * l
        )
    };
    let law = "stiffness = 1e5\ndissipation = 1.0\n";
    let mut text = String::from("[scene]\ngravity = [0.0, 0.0, -9.81]\n");
    for k in 0..n {
        text += &format!(
            "[[bodies]]\nname = \"l{k}\"\nmass = 0.1\ninertia = [2e-5, 1e-4, 1e-4]\nposition = [{:?}, 0.0, {r:?}]\n",
            (k as f64 + 0.5) * l
        );
    }
    for k in 1..n {
        text += &format!(
            "[[joints]]\nname = \"j{k}\"\ntype = \"spherical\"\nbodies = [\"l{}\", \"l{k}\"]\nat = [{:?}, 0.0, {r:?}]\n",
            k - 1,
            k as f64 * l
        );
    }
    for k in 0..n {
        text += &format!(
            "[[forces]]\nname = \"floor{k}\"\ntype = \"capsule-plane\"\nbody = \"l{k}\"\nradius = {r:?}\nat = {}\n\
             plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n{law}",
            segment(k)
        );
    }
    match mode {
        "group" => {
            let members: Vec<String> = (0..n)
                .map(|k| format!("{{ body = \"l{k}\", at = {}, radius = {r:?} }}", segment(k)))
                .collect();
            text += &format!(
                "[[forces]]\nname = \"self\"\ntype = \"capsule-group\"\nmembers = [{}]\n{law}",
                members.join(", ")
            );
        }
        "pairs" => {
            for i in 0..n {
                for j in i + 2..n {
                    text += &format!(
                        "[[forces]]\nname = \"p{i}_{j}\"\ntype = \"capsule-capsule\"\nbodies = [\"l{i}\", \"l{j}\"]\n\
                         segments = [{}, {}]\nradii = [{r:?}, {r:?}]\n{law}",
                        segment(i),
                        segment(j)
                    );
                }
            }
        }
        _ => {}
    }
    Scene::from_toml(&text, "chain on a floor").expect("the chain's scene")
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    let mut group = c.benchmark_group("capsule-chain-forces");
    for n in [16, 32, 64, 128, 256] {
        for mode in ["none", "group", "pairs"] {
            if mode == "pairs" && n > 64 {
                continue;
            }
            let scene = chain(n, mode);
            let system = scene.model.as_system();
            let (q, v) = (scene.q.clone(), scene.qd.clone());
            let mut out = vec![0.0; v.len()];
            group.bench_function(BenchmarkId::new(mode, n), |b| {
                b.iter(|| {
                    out.iter_mut().for_each(|x| *x = 0.0);
                    system.applied_forces(0.0, &q, &v, &mut out);
                    out[0]
                })
            });
        }
    }
    group.finish();
    c.final_summary();
}
