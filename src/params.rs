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

/// The keyword enum of a registered family of laws (friction laws, materials): each kind has
/// a scene keyword and declared parameters. The key lists, lookups, parsing and building from
/// given values are the same for every family and are provided here; [`law_kind_impls!`]
/// adds `Display`, `FromStr` and serde through the keyword.
pub trait LawKind: Copy + PartialEq + 'static {
    /// The law the kind builds.
    type Law;
    /// What the keyword names in messages ("friction law", "material model").
    const WHAT: &'static str;

    /// Every kind, in registration order.
    fn kinds() -> &'static [Self];
    /// The scene keyword of this kind.
    fn keyword(self) -> &'static str;
    /// The parameters of this kind, in their declared order.
    fn declared(self) -> &'static [ParamSpec];
    /// The law of this kind from its parameter values, in the order of [`Self::declared`].
    fn build_law(self, values: &[f64]) -> Self::Law;

    /// Every parameter key of any law, once each, in registration order (the first law that
    /// declares a key fixes its place).
    fn all_keys() -> Vec<&'static str> {
        let mut keys: Vec<&'static str> = Vec::new();
        for kind in Self::kinds() {
            for p in kind.declared() {
                if !keys.contains(&p.key) {
                    keys.push(p.key);
                }
            }
        }
        keys
    }

    /// The declaration of parameter `key` by the first law that has it.
    fn param(key: &str) -> Option<&'static ParamSpec> {
        Self::kinds()
            .iter()
            .flat_map(|k| k.declared())
            .find(|p| p.key == key)
    }

    /// The kinds whose parameters include `key`.
    fn laws_with(key: &str) -> Vec<Self> {
        Self::kinds()
            .iter()
            .copied()
            .filter(|k| k.declared().iter().any(|p| p.key == key))
            .collect()
    }

    /// The law of this kind from given values looked up by key; `Err(key)` names the first
    /// parameter that is missing. The values are not range-checked.
    fn build_from(self, given: impl Fn(&str) -> Option<f64>) -> Result<Self::Law, &'static str> {
        let values = self
            .declared()
            .iter()
            .map(|p| given(p.key).ok_or(p.key))
            .collect::<Result<Vec<f64>, _>>()?;
        Ok(self.build_law(&values))
    }

    /// The kind of a scene keyword, or the message naming the allowed ones.
    fn parse_keyword(s: &str) -> Result<Self, String> {
        let s = s.trim();
        match Self::kinds().iter().find(|k| k.keyword() == s) {
            Some(k) => Ok(*k),
            None => Err(format!(
                "unknown {} \"{s}\"; expected one of {}",
                Self::WHAT,
                Self::kinds()
                    .iter()
                    .map(|k| format!("\"{}\"", k.keyword()))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }
}

/// `Display`, `FromStr`, `Serialize` and `Deserialize` of a [`LawKind`] through its keyword.
macro_rules! law_kind_impls {
    ($kind:ty) => {
        impl std::fmt::Display for $kind {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::params::LawKind::keyword(*self))
            }
        }

        impl std::str::FromStr for $kind {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                <$kind as $crate::params::LawKind>::parse_keyword(s)
            }
        }

        impl serde::Serialize for $kind {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str($crate::params::LawKind::keyword(*self))
            }
        }

        impl<'de> serde::Deserialize<'de> for $kind {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = <String as serde::Deserialize>::deserialize(d)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }
    };
}
pub(crate) use law_kind_impls;
