//! Reference results of `shared/anchors` (scipy DOP853, rtol = atol = 1e-12, of an index-1 DAE in
//! body coordinates), copied from `shared/anchors/results/reference.json`, and the error measure
//! that protocol uses.

/// Four-bar `[x, y, θ, vx, vy, ω]` of crank, coupler, rocker (centres of mass) at t = 1 s
/// (angles wrapped to [0, 2π) in the source).
pub const FOURBAR_1S: [[f64; 6]; 3] = [
    [
        0.39086516984116365,
        -0.3118083049005543,
        5.609824677472552,
        0.2817451225029032,
        0.35317967298567776,
        0.9035844077104529,
    ],
    [
        2.0290237483794917,
        -0.7058306756334527,
        -0.06581876472583136,
        0.571100712102016,
        0.8218199469049838,
        0.09256891772901597,
    ],
    [
        2.6381585785383286,
        -0.39402237073290275,
        -0.5531418641762115,
        0.2893555895991149,
        0.46864027391929525,
        0.7343633536866413,
    ],
];

/// Slider-crank `[x, y, θ, vx, vy, ω]` of crank, rod, slider at t = 1 s.
pub const SLIDERCRANK_1S: [[f64; 6]; 3] = [
    [
        -0.23286528486525646,
        -0.09096020615984743,
        -2.7692046233654493,
        -0.695958689839095,
        1.7817090066709516,
        -7.65124354066921,
    ],
    [
        0.5301239582480174,
        -0.0909602061598475,
        0.09108610594678586,
        -1.2291781301086389,
        1.7817090066709522,
        -1.7891257775245648,
    ],
    [
        1.5259784862265493,
        4.645431407288335e-16,
        0.0,
        -1.0664388805390808,
        2.5588604425216785e-15,
        0.0,
    ],
];

/// Largest absolute errors `(positions and angles, velocities)` of body states `q`, `q̇` against
/// reference rows `[x, y, θ, vx, vy, ω]`; angle differences are taken modulo 2π.
pub fn state_errors(q: &[f64], qd: &[f64], reference: &[[f64; 6]]) -> (f64, f64) {
    let tau = std::f64::consts::TAU;
    let (mut ep, mut ev) = (0.0f64, 0.0f64);
    for (k, r) in reference.iter().enumerate() {
        let dth = (q[3 * k + 2] - r[2]).rem_euclid(tau);
        ep = ep
            .max((q[3 * k] - r[0]).abs())
            .max((q[3 * k + 1] - r[1]).abs())
            .max(dth.min(tau - dth));
        ev = ev
            .max((qd[3 * k] - r[3]).abs())
            .max((qd[3 * k + 1] - r[4]).abs())
            .max((qd[3 * k + 2] - r[5]).abs());
    }
    (ep, ev)
}
