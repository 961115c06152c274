//! Numbers in messages and files: the shortest form that reads back exactly.

use std::fmt;

/// Displays an `f64` in its shortest round-trip form: plain decimals for magnitudes from 1e-5 to
/// 1e16, scientific notation outside (`5e305`, not 306 digits; `1e-300`, not 302), `0` for both
/// zeros. Both forms read back to the same number.
///
/// ```
/// use dalembert_system::Shortest;
/// assert_eq!(Shortest(5e305).to_string(), "5e305");
/// assert_eq!(Shortest(0.1 + 0.2).to_string(), "0.30000000000000004");
/// assert_eq!(Shortest(-0.0).to_string(), "0");
/// assert_eq!(Shortest(2.5e-7).to_string(), "2.5e-7");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shortest(pub f64);

impl fmt::Display for Shortest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        let a = x.abs();
        if a == 0.0 {
            // -0 prints as 0: a sign on zero only confuses a reader.
            f.write_str("0")
        } else if !a.is_finite() || (1e-5..1e16).contains(&a) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}
