//! Overrides of a scene file (`--set key=value`, `--grid`, `--bins`, or Python's keywords), applied to its TOML
//! before validation, and the resolved scene's canonical key list, which `scene_info` records and a
//! checkpoint compares.

use toml::{Table, Value};

/// Overrides applied on top of a scene file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// `capture.grid = [n, n]`.
    pub grid: Option<usize>,
    /// `capture.bins`.
    pub bins: Option<usize>,
    /// `key=value` pairs: a dotted key (`medium.albedo`, `object[1].center`) and a TOML value; a value
    /// that is not TOML is taken as a string (`relay.kind=wall`).
    pub set: Vec<String>,
    /// How the user wrote them, so that an error quotes the user's own words.
    pub spelling: Spelling,
}

pub use murk_core::Spelling;

/// One override as the user wrote it: `--grid 64` or `grid=64`.
fn quote(spelling: Spelling, name: &str, value: &str) -> String {
    match spelling {
        Spelling::Cli => format!("--{name} {value}"),
        Spelling::Python if name == "set" => format!("set item {value:?}"),
        Spelling::Python => format!("{name}={value}"),
    }
}

/// How to give one more `set` entry.
fn one_set(spelling: Spelling) -> &'static str {
    match spelling {
        Spelling::Cli => "give one KEY=VALUE per --set",
        Spelling::Python => "give one KEY=VALUE per item of set",
    }
}

impl Overrides {
    /// Every override as (dotted key, value, how the user wrote it), the grid and bins included.
    pub(crate) fn assignments(&self) -> Result<Vec<(String, Value, String)>, String> {
        let mut out = Vec::new();
        let quote = |name: &str, value: &dyn std::fmt::Display| {
            quote(self.spelling, name, &value.to_string())
        };
        // TOML integers are i64: a larger count is refused, not wrapped to a negative one.
        let int = |n: usize, name: &str| {
            i64::try_from(n)
                .map(Value::Integer)
                .map_err(|_| format!("{}: too large", quote(name, &n)))
        };
        if let Some(n) = self.grid {
            let v = Value::Array(vec![int(n, "grid")?, int(n, "grid")?]);
            out.push(("capture.grid".into(), v, quote("grid", &n)));
        }
        if let Some(b) = self.bins {
            out.push(("capture.bins".into(), int(b, "bins")?, quote("bins", &b)));
        }
        for s in &self.set {
            let written = quote("set", s);
            let (k, v) = s
                .split_once('=')
                .ok_or_else(|| format!("{written}: expected KEY=VALUE, e.g. medium.albedo=0.83"))?;
            let (k, v) = (k.trim(), v.trim());
            if k.is_empty() {
                return Err(format!("{written}: the key is empty"));
            }
            if v.contains('\n') {
                // A second line would be read as a second assignment and dropped.
                // Python's quoting already escapes the line break.
                let shown = match self.spelling {
                    Spelling::Cli => quote("set", &s.escape_debug()),
                    Spelling::Python => written,
                };
                return Err(format!(
                    "{shown}: the value spans lines; {}",
                    one_set(self.spelling)
                ));
            }
            // One setting from two places: whichever came last would win unseen.
            if let Some((_, _, first)) = out.iter().find(|(key, ..)| key == k) {
                return Err(format!("{written}: {k} is also set by {first}"));
            }
            out.push((k.to_string(), parse_value(v), written));
        }
        Ok(out)
    }
}

/// A TOML value, or the text as a string when it is not one.
fn parse_value(v: &str) -> Value {
    format!("v = {v}")
        .parse::<Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| Value::String(v.to_string()))
}

/// One step of a dotted key: a table key, optionally indexing an array of tables (`object[1]`).
fn segment(s: &str) -> Result<(&str, Option<usize>), String> {
    match s.split_once('[') {
        None => Ok((s, None)),
        Some((name, rest)) => {
            let i = rest
                .strip_suffix(']')
                .and_then(|i| i.parse().ok())
                .ok_or_else(|| format!("'{s}' is not NAME or NAME[INDEX]"))?;
            Ok((name, Some(i)))
        }
    }
}

/// Sets `key` (dotted) to `value` in `table`, creating missing tables on the way.
pub(crate) fn apply(table: &mut Table, key: &str, value: Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("'{key}' has an empty part"));
    }
    let mut t = table;
    for (depth, part) in parts.iter().enumerate() {
        let (name, index) = segment(part)?;
        let last = depth + 1 == parts.len();
        let slot = match index {
            None if last => {
                t.insert(name.to_string(), value);
                return Ok(());
            }
            None => t
                .entry(name.to_string())
                .or_insert_with(|| Value::Table(Table::new())),
            Some(i) => {
                let Some(Value::Array(items)) = t.get_mut(name) else {
                    return Err(format!("'{name}' is not a list of tables in the scene"));
                };
                let n = items.len();
                let item = items.get_mut(i).ok_or_else(|| {
                    format!("{name}[{i}] does not exist (the scene has {n} of them)")
                })?;
                if last {
                    *item = value;
                    return Ok(());
                }
                item
            }
        };
        t = match slot {
            Value::Table(inner) => inner,
            _ => {
                let upto = parts[..=depth].join(".");
                return Err(format!("'{upto}' is a value, not a table"));
            }
        };
    }
    Ok(())
}

/// The resolved scene as sorted `key = value` lines (comments and layout dropped), so that two renders
/// compare by what they compute, and a difference names its key.
pub(crate) fn canonical(table: &Table) -> String {
    let mut lines = Vec::new();
    flatten("", &Value::Table(table.clone()), &mut lines);
    lines.join("\n")
}

fn flatten(prefix: &str, v: &Value, out: &mut Vec<String>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        Value::Table(t) => t.iter().for_each(|(k, v)| flatten(&join(k), v, out)),
        Value::Array(items) if !items.is_empty() && items.iter().all(Value::is_table) => items
            .iter()
            .enumerate()
            .for_each(|(i, v)| flatten(&format!("{prefix}[{i}]"), v, out)),
        v => out.push(format!("{prefix} = {v}")),
    }
}

/// The keys whose values differ between two canonical listings, as "key: A there, B here" (at most
/// `max` of them).
pub(crate) fn differences(there: &str, here: &str, max: usize) -> Vec<String> {
    let split = |s: &str| -> std::collections::BTreeMap<String, String> {
        s.lines()
            .filter_map(|l| l.split_once(" = "))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let (a, b) = (split(there), split(here));
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .take(max)
        .map(|k| {
            let show = |m: &std::collections::BTreeMap<String, String>| {
                m.get(k).cloned().unwrap_or_else(|| "unset".into())
            };
            format!("{k} is {} there, {} now", show(&a), show(&b))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(s: &str) -> Table {
        s.parse().unwrap()
    }

    #[test]
    fn sets_nested_keys_and_list_items() {
        let mut t = table(
            "[medium]\nmu_t = 1.0\n[[object]]\nshape = \"quad\"\n[[object]]\nshape = \"box\"\n",
        );
        apply(&mut t, "medium.albedo", parse_value("0.83")).unwrap();
        apply(&mut t, "object[1].albedo", parse_value("0.5")).unwrap();
        apply(&mut t, "relay.kind", parse_value("wall")).unwrap();
        apply(&mut t, "capture.grid", parse_value("[8, 8]")).unwrap();
        assert_eq!(
            canonical(&t),
            "capture.grid = [8, 8]\nmedium.albedo = 0.83\nmedium.mu_t = 1.0\nobject[0].shape = \"quad\"\n\
             object[1].albedo = 0.5\nobject[1].shape = \"box\"\nrelay.kind = \"wall\""
        );
        assert!(apply(&mut t, "object[2].albedo", parse_value("1"))
            .unwrap_err()
            .contains("object[2] does not exist"));
        assert!(apply(&mut t, "medium.mu_t.x", parse_value("1"))
            .unwrap_err()
            .contains("'medium.mu_t' is a value"));
        assert!(apply(&mut t, "medium..g", parse_value("1")).is_err());
    }

    #[test]
    fn differences_name_the_key() {
        let a = "capture.grid = [32, 32]\nmedium.g = 0.0\nspp = 4";
        let b = "capture.grid = [64, 64]\nmedium.g = 0.0\nspp = 4\nmedium.ior = 1.3";
        assert_eq!(
            differences(a, b, 5),
            [
                "capture.grid is [32, 32] there, [64, 64] now",
                "medium.ior is unset there, 1.3 now"
            ]
        );
        assert!(differences(a, a, 5).is_empty());
    }
}
