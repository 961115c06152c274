//! The integration methods, one file (or folder) each: its [`Stepper`](crate::Stepper), its
//! [`MethodEntry`](crate::MethodEntry) and its typed [`Method`](crate::Method) constructor.

pub(crate) mod ali3p;
pub(crate) mod dopri5;
pub(crate) mod first_order;
pub(crate) mod generalized_alpha;
pub(crate) mod rk4;
pub(crate) mod symplectic_euler;
