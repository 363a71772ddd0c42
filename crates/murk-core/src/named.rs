//! Closed sets of options under the names the CLI, the Python module and scene files use, kept in
//! one table per set so that every front end accepts and lists the same names.

use crate::{Error, Result};

/// An option set with one name per value.
pub trait Named: Copy + PartialEq + 'static {
    /// What the option is, for messages ("falloff").
    const WHAT: &'static str;
    /// Every value with its name.
    const CHOICES: &'static [(&'static str, Self)];

    /// The value called `name`; an unknown name is refused listing the others.
    fn named(name: &str) -> Result<Self> {
        Self::CHOICES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::CHOICES.iter().map(|(n, _)| *n).collect();
                Error::param(format!(
                    "{} '{name}': expected {}",
                    Self::WHAT,
                    names.join(", ")
                ))
            })
    }

    /// This value's name.
    fn name(self) -> &'static str {
        Self::CHOICES
            .iter()
            .find(|(_, v)| *v == self)
            .map(|(n, _)| *n)
            .expect("every value is in CHOICES")
    }
}

impl Named for crate::window::WindowEnd {
    const WHAT: &'static str = "window end";
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("auto", Self::Auto),
        ("taper", Self::Taper),
        ("keep", Self::Keep),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::window::WindowEnd;

    #[test]
    fn names_round_trip_and_unknown_ones_list_the_choices() {
        for &(n, v) in WindowEnd::CHOICES {
            assert_eq!(WindowEnd::named(n).unwrap(), v);
            assert_eq!(v.name(), n);
        }
        let e = WindowEnd::named("never").unwrap_err().to_string();
        assert_eq!(e, "window end 'never': expected auto, taper, keep");
    }
}
