//! The one line a command-line tool prints for an error: murk's tools promise a single line that
//! names the file and the problem.

/// `e` and its causes joined with ": ", outermost first, skipping a cause that the text before it
/// already ends with (murk's I/O errors print their source themselves); a line break (a path may
/// hold one) is written as `\n` or `\r`.
pub fn error_line(e: &(dyn std::error::Error + 'static)) -> String {
    let mut msg = String::new();
    let mut cause = Some(e);
    while let Some(c) = cause {
        let text = c.to_string();
        if !msg.ends_with(&text) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(&text);
        }
        cause = c.source();
    }
    msg.replace('\n', "\\n").replace('\r', "\\r")
}

/// clap's message on one line: its lines up to the usage, joined (`the following required arguments
/// were not provided: --out <OUT>`, `invalid value 'x' for '--method <METHOD>' [possible values: …]`).
/// An argument of `args` holding a line break is quoted by clap as it is, so its breaks are written as
/// `\n` or `\r` first, as [`error_line`] writes them, rather than split into lines.
pub fn clap_one_line(text: &str, args: impl IntoIterator<Item = std::ffi::OsString>) -> String {
    let mut text = text.to_string();
    for arg in args {
        let arg = arg.to_string_lossy().into_owned();
        if arg.contains(['\n', '\r']) {
            text = text.replace(&arg, &arg.replace('\n', "\\n").replace('\r', "\\r"));
        }
    }
    text.lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(|l| l.trim().trim_start_matches("error: "))
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct Layer(&'static str, Option<Box<Layer>>);
    impl std::fmt::Display for Layer {
        fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
    }
    impl std::error::Error for Layer {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            self.1.as_deref().map(|l| l as _)
        }
    }

    #[test]
    fn causes_join_once_on_one_line() {
        let os = Layer("No such file (os error 2)", None);
        let io = Layer("a\nb.mat: No such file (os error 2)", Some(Box::new(os)));
        let top = Layer("reading the capture", Some(Box::new(io)));
        assert_eq!(
            error_line(&top),
            "reading the capture: a\\nb.mat: No such file (os error 2)"
        );
        assert_eq!(
            clap_one_line(
                "error: invalid value '-1' for '--runs <RUNS>'\n\nFor more information, try '--help'.\n",
                ["murk-bench".into(), "--runs".into(), "-1".into()]
            ),
            "invalid value '-1' for '--runs <RUNS>'"
        );
        assert_eq!(
            clap_one_line(
                "error: invalid value 'a\nb' for '--method <METHOD>'\n\nUsage: murk\n",
                ["murk".into(), "--method".into(), "a\nb".into()]
            ),
            "invalid value 'a\\nb' for '--method <METHOD>'"
        );
    }
}
