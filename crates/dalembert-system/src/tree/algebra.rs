//! Spatial (Plücker) vector algebra for the tree recursions, in 3 × 3 blocks (Featherstone, *Rigid
//! Body Dynamics Algorithms*, 2008, ch. 2). A motion vector is `[ω; v_O]`, a force vector `[n_O; f]`,
//! both taken at a frame's origin `O` and in that frame's axes.

use nalgebra::{Matrix3, Vector3};

/// A 3-vector.
pub type V3 = Vector3<f64>;
/// A 3 × 3 matrix.
pub type M3 = Matrix3<f64>;

/// A spatial vector as its two 3-vector halves: `[ω; v]` (motion) or `[n; f]` (force).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sv {
    /// Angular half (`ω` or the moment `n`).
    pub w: V3,
    /// Linear half (`v` or the force `f`).
    pub v: V3,
}

impl Sv {
    /// The zero vector.
    pub const ZERO: Sv = Sv {
        w: V3::new(0.0, 0.0, 0.0),
        v: V3::new(0.0, 0.0, 0.0),
    };

    /// `[w; v]`.
    pub fn new(w: V3, v: V3) -> Self {
        Sv { w, v }
    }

    /// `self · other` (a motion with a force gives power).
    #[inline]
    pub fn dot(&self, o: &Sv) -> f64 {
        self.w.dot(&o.w) + self.v.dot(&o.v)
    }

    /// `self × m` for motions (`crm`): `[ω × m_w; ω × m_v + v × m_w]`.
    #[inline]
    pub fn cross_motion(&self, m: &Sv) -> Sv {
        Sv::new(self.w.cross(&m.w), self.w.cross(&m.v) + self.v.cross(&m.w))
    }

    /// `self ×* f` for a force (`crf`): `[ω × n + v × f; ω × f]`.
    #[inline]
    pub fn cross_force(&self, f: &Sv) -> Sv {
        Sv::new(self.w.cross(&f.w) + self.v.cross(&f.v), self.w.cross(&f.v))
    }

    /// `self * s`.
    #[inline]
    pub fn scale(&self, s: f64) -> Sv {
        Sv::new(self.w * s, self.v * s)
    }
}

impl std::ops::Add for Sv {
    type Output = Sv;
    #[inline]
    fn add(self, o: Sv) -> Sv {
        Sv::new(self.w + o.w, self.v + o.v)
    }
}

impl std::ops::AddAssign for Sv {
    #[inline]
    fn add_assign(&mut self, o: Sv) {
        self.w += o.w;
        self.v += o.v;
    }
}

/// The Plücker transform of motion vectors from a frame `A` to a frame `B` whose origin is `r`
/// (in `A`'s axes) and whose axes are `A`'s rotated by `Eᵀ`: `X = [[E, 0], [−E r×, E]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Rotation from `A`'s components to `B`'s (`x_B = E x_A`).
    pub e: M3,
    /// `B`'s origin in `A`'s frame.
    pub r: V3,
}

impl Transform {
    /// The identity.
    pub fn identity() -> Self {
        Transform {
            e: M3::identity(),
            r: V3::zeros(),
        }
    }

    /// `X m` for a motion vector: `[E ω; E (v − r × ω)]`.
    #[inline]
    pub fn motion(&self, m: &Sv) -> Sv {
        Sv::new(self.e * m.w, self.e * (m.v - self.r.cross(&m.w)))
    }

    /// `Xᵀ f` for a force vector in `B`, giving it in `A`: `[Eᵀ n + r × Eᵀ f; Eᵀ f]`.
    #[inline]
    pub fn force_back(&self, f: &Sv) -> Sv {
        let (n, ff) = (self.e.tr_mul(&f.w), self.e.tr_mul(&f.v));
        Sv::new(n + self.r.cross(&ff), ff)
    }
}

/// A symmetric spatial inertia (rigid-body or articulated) `[[A, B], [Bᵀ, C]]` acting on motion
/// vectors and giving force vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertia {
    /// Angular–angular block (symmetric).
    pub a: M3,
    /// Angular–linear block.
    pub b: M3,
    /// Linear–linear block (symmetric).
    pub c: M3,
}

impl Inertia {
    /// The zero inertia.
    pub fn zeros() -> Self {
        Inertia {
            a: M3::zeros(),
            b: M3::zeros(),
            c: M3::zeros(),
        }
    }

    /// A rigid body of mass `m`, centre of mass `com` and inertia `i_com` about it, about the frame
    /// origin: `[[I_c + m c× c×ᵀ, m c×], [m c×ᵀ, m 1]]` (Featherstone eq. 2.63).
    pub fn rigid(m: f64, com: &V3, i_com: &M3) -> Self {
        let cx = com.cross_matrix();
        Inertia {
            a: i_com + cx * cx.transpose() * m,
            b: cx * m,
            c: M3::identity() * m,
        }
    }

    /// `I m`.
    #[inline]
    pub fn mul(&self, m: &Sv) -> Sv {
        Sv::new(self.a * m.w + self.b * m.v, self.b.tr_mul(&m.w) + self.c * m.v)
    }

    /// `Xᵀ I X` for `X` from the parent `A` to this inertia's frame `B`: the inertia in `A`. With
    /// `X = diag(E, E) [[1, 0], [−r×, 1]]` and `A', B', C'` the blocks rotated by `E`:
    /// `[[A' − B' r× + r× B'ᵀ − r× C' r×, B' + r× C'], [·, C']]`.
    pub fn transform_back(&self, x: &Transform) -> Inertia {
        let (e, rx) = (&x.e, x.r.cross_matrix());
        let a = e.tr_mul(&(self.a * e));
        let b = e.tr_mul(&(self.b * e));
        let c = e.tr_mul(&(self.c * e));
        let b_rx = b * rx;
        let rx_c = rx * c;
        Inertia {
            a: a - b_rx - b_rx.transpose() - rx_c * rx,
            b: b + rx_c,
            c,
        }
    }

    /// `self += o`.
    #[inline]
    pub fn add(&mut self, o: &Inertia) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }

    /// `self −= u uᵀ / d` (the articulated-body update of Featherstone's table 7.1).
    #[inline]
    pub fn sub_outer(&mut self, u: &Sv, d: f64) {
        let s = 1.0 / d;
        self.a -= u.w * u.w.transpose() * s;
        self.b -= u.w * u.v.transpose() * s;
        self.c -= u.v * u.v.transpose() * s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dense 6 × 6 forms, written from the definitions.
    fn dense_x(x: &Transform) -> nalgebra::Matrix6<f64> {
        let mut m = nalgebra::Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&x.e);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&x.e);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-x.e * x.r.cross_matrix()));
        m
    }

    fn dense_i(i: &Inertia) -> nalgebra::Matrix6<f64> {
        let mut m = nalgebra::Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&i.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&i.b);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&i.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&i.c);
        m
    }

    fn six(s: &Sv) -> nalgebra::Vector6<f64> {
        nalgebra::Vector6::new(s.w.x, s.w.y, s.w.z, s.v.x, s.v.y, s.v.z)
    }

    /// The block forms equal the 6 × 6 products of the definitions to round-off (1e-13 of
    /// entries of order 1).
    #[test]
    fn block_forms_equal_the_dense_products() {
        let e = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let x = Transform {
            e,
            r: V3::new(0.7, -0.2, 1.3),
        };
        let i = Inertia::rigid(
            2.5,
            &V3::new(0.1, 0.4, -0.3),
            &M3::new(0.5, 0.1, 0.0, 0.1, 0.7, 0.05, 0.0, 0.05, 0.9),
        );
        let m = Sv::new(V3::new(0.3, -0.8, 1.1), V3::new(-0.4, 0.2, 0.9));
        let close = |a: nalgebra::Vector6<f64>, b: nalgebra::Vector6<f64>| (a - b).amax() < 1e-13;
        assert!(close(six(&x.motion(&m)), dense_x(&x) * six(&m)));
        assert!(close(six(&x.force_back(&m)), dense_x(&x).transpose() * six(&m)));
        assert!(close(six(&i.mul(&m)), dense_i(&i) * six(&m)));
        let back = dense_x(&x).transpose() * dense_i(&i) * dense_x(&x);
        assert!((dense_i(&i.transform_back(&x)) - back).amax() < 1e-13);
        // crf is minus the transpose of crm: (v ×* f)·m = −f·(v × m).
        let f = Sv::new(V3::new(1.0, 2.0, -0.5), V3::new(0.3, 0.1, 0.2));
        assert!((m.cross_force(&f).dot(&x.motion(&m)) + f.dot(&m.cross_motion(&x.motion(&m)))).abs() < 1e-13);
    }
}
