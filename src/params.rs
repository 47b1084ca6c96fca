//! How a physical law declares its numeric parameters to the scene file: a key, what the value
//! is, its unit and its admissible range. The friction laws ([`crate::contact::FrictionLawSpec`])
//! and the materials ([`crate::material::MaterialLawSpec`]) declare theirs next to their physics;
//! the scene's key lists, reference tables, range checks and messages are made from these
//! declarations, so that a new law needs no scene code of its own.

/// The lower bound of a parameter's admissible range (every parameter must also be finite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// value > lo.
    Above(f64),
    /// value ≥ lo.
    AtLeast(f64),
    /// Any finite value (e.g. a higher-order coefficient that may be negative).
    Finite,
}

impl Bound {
    /// Whether `x` is finite and within the bound.
    pub fn admits(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Bound::Above(lo) => x > lo,
                Bound::AtLeast(lo) => x >= lo,
                Bound::Finite => true,
            }
    }
}

impl std::fmt::Display for Bound {
    /// `> 0`, `>= 1`, `finite`: how the scene's messages and reference write the bound.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Bound::Above(lo) => write!(f, "> {lo}"),
            Bound::AtLeast(lo) => write!(f, ">= {lo}"),
            Bound::Finite => write!(f, "finite"),
        }
    }
}

/// One parameter of a law as a scene file gives it: a number under `key` in the law's section
/// (`[friction]`, `[material]`), with what it is, its unit and its bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Key in the law's section (`mu`, `eps`, `c1`, ...).
    pub key: &'static str,
    /// What the value is, as messages name it ("friction coefficient μ").
    pub what: &'static str,
    /// Unit in the scene's L-F-T system (`–` for dimensionless).
    pub unit: &'static str,
    /// Admissible range.
    pub bound: Bound,
    /// More about the value for the scene reference ("" for nothing).
    pub note: &'static str,
}
