//! A tolerant look at y-tal's `scene_info` YAML for display. PyYAML's default dumper writes
//! Python-only tags (`!!python/object/apply:numpy...`, `!!python/object/apply:tal.enums...`) that
//! no YAML library outside Python resolves, so this reads the block-style layout PyYAML emits
//! line by line instead of parsing YAML.

const MAX_VALUE_CHARS: usize = 60;

/// Top-level keys of `yaml` with a short, human-readable value each, in file order. Nested
/// mappings show their keys (`{a, b}`), sequences of plain values their values (else their length),
/// blocks of text their line count, numpy arrays `<numpy array>`, y-tal enums `Name(value)`. Lines that do not look like `key: value` are skipped; this never fails.
pub fn scene_info_summary(yaml: &str) -> Vec<(String, String)> {
    let lines: Vec<&str> = yaml
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#') && *l != "---")
        .collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.starts_with([' ', '\t', '-']) {
            continue;
        }
        let Some((key, rest)) = split_key(line) else {
            continue;
        };
        // The indented (or "- " sequence) lines that belong to this key.
        let block: Vec<&str> = lines[i + 1..]
            .iter()
            .take_while(|l| l.starts_with([' ', '\t', '-']))
            .copied()
            .collect();
        out.push((unquote(key).to_string(), describe(rest.trim(), &block)));
    }
    out
}

/// `key: rest` with the first ": " (or a trailing ':') outside quotes.
fn split_key(line: &str) -> Option<(&str, &str)> {
    if let Some(k) = line.strip_suffix(':') {
        if !k.contains(": ") {
            return Some((k, ""));
        }
    }
    let (k, v) = line.split_once(": ")?;
    Some((k.trim(), v))
}

fn unquote(s: &str) -> &str {
    let s = s.trim();
    for q in ['\'', '"'] {
        if let Some(inner) = s.strip_prefix(q).and_then(|r| r.strip_suffix(q)) {
            return inner;
        }
    }
    s
}

fn describe(inline: &str, block: &[&str]) -> String {
    if let Some(tag) = inline.strip_prefix("!!python/object/apply:") {
        let tag = tag.split_whitespace().next().unwrap_or(tag);
        if tag.starts_with("numpy") {
            return "<numpy array>".into();
        }
        let short = tag.rsplit('.').next().unwrap_or(tag);
        return match block {
            [only] => format!("{short}({})", unquote(only.trim_start_matches(['-', ' ']))),
            _ => format!("<{short}>"),
        };
    }
    if let Some(tag) = inline.strip_prefix("!!") {
        return format!("<{}>", tag.split_whitespace().next().unwrap_or(tag));
    }
    // A literal or folded block of text (murk's own scene, as TOML): its size, not a lone "|".
    if inline.starts_with(['|', '>']) {
        return format!("text of {} lines", block.len());
    }
    if inline.is_empty() {
        if block.is_empty() {
            return String::new();
        }
        let first = block[0];
        let indent = first.len() - first.trim_start().len();
        if first.trim_start().starts_with("- ") || first.trim_start() == "-" {
            let items: Vec<&str> = block
                .iter()
                .filter(|l| {
                    l.len() - l.trim_start().len() == indent && l.trim_start().starts_with('-')
                })
                .map(|l| l.trim_start()[1..].trim())
                .collect();
            // Plain values are listed (as far as they fit); nested ones are counted.
            let plain = block.len() == items.len()
                && items.iter().all(|i| !i.is_empty() && !i.contains(": "));
            let list = items
                .iter()
                .map(|i| unquote(i))
                .collect::<Vec<_>>()
                .join(", ");
            return if plain && list.chars().count() <= MAX_VALUE_CHARS {
                format!("[{list}]")
            } else if plain {
                let cut: String = list.chars().take(MAX_VALUE_CHARS - 1).collect();
                format!("[{cut}…] ({} items)", items.len())
            } else if items.len() == 1 {
                "1 entry".into()
            } else {
                format!("{} entries", items.len())
            };
        }
        let keys: Vec<&str> = block
            .iter()
            .filter(|l| {
                // PyYAML writes nested sequences unindented ("key:\n- item").
                l.len() - l.trim_start().len() == indent && !l.trim_start().starts_with('-')
            })
            .filter_map(|l| split_key(l.trim_start()).map(|(k, _)| unquote(k)))
            .collect();
        let mut s = format!(
            "{{{}",
            keys.iter().take(6).copied().collect::<Vec<_>>().join(", ")
        );
        if keys.len() > 6 {
            s.push_str(&format!(", … {} more", keys.len() - 6));
        }
        s.push('}');
        return s;
    }
    let v = unquote(inline);
    if v.chars().count() > MAX_VALUE_CHARS {
        let cut: String = v.chars().take(MAX_VALUE_CHARS - 1).collect();
        format!("{cut}…")
    } else {
        v.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What PyYAML's default dumper writes for a y-tal render (abridged).
    const TAL_YAML: &str = "args:\n  config: scene.yaml\n  threads: 4\nconfig:\n  name: Z\n  sensor_width: 64\n  geometry:\n  - name: Z\n    mesh: z.obj\nground_truth:\n  depth: !!python/object/apply:numpy.core.multiarray._reconstruct\n    args:\n    - !!python/name:numpy.ndarray ''\n  format: !!python/object/apply:tal.enums.GroundTruthFormat\n  - 1\nfmt: !!python/object/apply:tal.enums.GroundTruthFormat\n- 1\nis_polarized: false\noriginal_nt: 4096\ntal_version: '0.20.0'\nlist:\n- 1\n- 2\n- 3\ngt: !!python/object/apply:numpy._core.multiarray._reconstruct\n  args: []\n";

    #[test]
    fn summarises_tal_scene_info() {
        let s = scene_info_summary(TAL_YAML);
        let get = |k: &str| s.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str());
        assert_eq!(get("args"), Some("{config, threads}"));
        assert_eq!(get("config"), Some("{name, sensor_width, geometry}"));
        assert_eq!(get("ground_truth"), Some("{depth, format}"));
        assert_eq!(get("fmt"), Some("GroundTruthFormat(1)"));
        assert_eq!(get("original_nt"), Some("4096"));
        assert_eq!(get("tal_version"), Some("0.20.0"));
        assert_eq!(get("list"), Some("[1, 2, 3]"));
        assert_eq!(get("gt"), Some("<numpy array>"));
        assert_eq!(s.len(), 9);
    }

    /// murk's own renders: overrides listed, not counted; the scene's TOML block sized, not "|".
    #[test]
    fn summarises_murk_scene_info() {
        let yaml = "generator: murk render\noverrides:\n- 'medium.mu_t=0.0'\n- 'capture.grid=[64, 64]'\nscene: |\n  [medium]\n  mu_t = 0.0\nlong:\n- aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\n- b\nnested:\n- name: Z\n  mesh: z.obj\n";
        let s = scene_info_summary(yaml);
        let get = |k: &str| s.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str());
        assert_eq!(
            get("overrides"),
            Some("[medium.mu_t=0.0, capture.grid=[64, 64]]")
        );
        assert_eq!(get("scene"), Some("text of 2 lines"));
        assert!(get("long").unwrap().ends_with("…] (2 items)"), "{s:?}");
        assert_eq!(get("nested"), Some("1 entry"));
    }

    #[test]
    fn tolerates_anything() {
        assert!(scene_info_summary("").is_empty());
        assert!(scene_info_summary("{}\n").is_empty());
        assert!(scene_info_summary("- a\n- b\n").is_empty());
        let long = format!("k: {}", "x".repeat(200));
        assert_eq!(
            scene_info_summary(&long)[0].1.chars().count(),
            MAX_VALUE_CHARS
        );
        scene_info_summary(": : :\n\t\x00\n'q': \"v\"\n");
    }
}
