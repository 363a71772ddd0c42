//! The pieces every study page is made of, the report's and `murk demo`'s: the head with murk's
//! style, the provenance table, a figure, and the page written as `index.html`.

use super::io;
use crate::format::esc;
use murk_core::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The study pages' own layout on top of murk's shared look ([`murk_view::PAGE_STYLE`]): the sticky
/// switch bar, figures as wide as the page, plots in a compact grid.
const STYLE: &str = "<style>#controls{position:sticky;top:0;background:#f4f4f4;border-bottom:1px solid #bbb;padding:.4em .6em;z-index:1}\
figure{margin:.5em 0}.grid img{max-width:100%}figure.view{display:inline-block;margin:.5em 1em .5em 0;vertical-align:top;max-width:460px}\
.plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(380px,1fr));gap:4px}.plots img{width:100%}\
li{margin:.3em 0}</style>";

/// The page's start: the head with its title, the style, and the heading `h1`.
pub(crate) fn head(title: &str, h1: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{}</title>\n{}{STYLE}</head><body>\n<h1>{}</h1>\n",
        esc(title),
        murk_view::PAGE_STYLE,
        esc(h1)
    )
}

/// A key/value table (`id` `provenance` at the top of the page, `parameters` further down).
pub(crate) fn key_values<K: AsRef<str>, V: AsRef<str>>(id: &str, rows: &[(K, V)]) -> String {
    let mut h = format!("<table id=\"{id}\">");
    for (k, v) in rows {
        let _ = write!(
            h,
            "<tr><th>{}</th><td>{}</td></tr>",
            esc(k.as_ref()),
            esc(v.as_ref())
        );
    }
    h.push_str("</table>\n");
    h
}

/// A picture: `src` relative to the page.
pub(crate) fn img(src: &str, alt: &str) -> String {
    format!("<img src=\"{}\" alt=\"{}\">", esc(src), esc(alt))
}

/// A picture (`img`'s markup) with its caption, `class` choosing the layout (`grid`: page wide;
/// `view`: side by side).
pub(crate) fn figure(class: &str, img: &str, caption: &str) -> String {
    let caption = if caption.is_empty() {
        String::new()
    } else {
        format!("<figcaption>{}</figcaption>", esc(caption))
    };
    format!("<figure class=\"{class}\">{img}{caption}</figure>\n")
}

/// Ends the page and writes it as `dir/index.html` (atomically); returns its path.
pub(crate) fn write(dir: &Path, mut html: String) -> Result<PathBuf> {
    html.push_str("</body></html>\n");
    let path = dir.join("index.html");
    murk_io::write_atomic(&path, |w| w.write_all(html.as_bytes()).map_err(io(&path)))?;
    Ok(path)
}
