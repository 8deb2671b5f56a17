//! The report as one self-contained HTML page.

use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;

use crate::error::Result;

/// `markdown` (the subset [`markdown`] writes: headings, paragraphs, lists, tables, images,
/// inline code) as one HTML page, its pictures from `out` inlined.
pub(super) fn html(markdown: &str, out: &Path) -> Result<String> {
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>mvgrasp evaluation</title>\n\
         <style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}\
         table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;\
         font-size:90%}img{max-width:32%;margin:2px}code{background:#f3f3f3}</style>\n</head><body>\n",
    );
    let mut in_table = false;
    let mut in_list = false;
    for line in markdown.lines() {
        let is_row = line.starts_with('|');
        if in_table && !is_row {
            html.push_str("</table>\n");
            in_table = false;
        }
        let is_item = line.starts_with("- ");
        if in_list && !is_item {
            html.push_str("</ul>\n");
            in_list = false;
        }
        if is_row {
            let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
            if cells.iter().all(|c| c.chars().all(|ch| ch == '-')) {
                continue;
            }
            let tag = if in_table { "td" } else { "th" };
            if !in_table {
                html.push_str("<table>\n");
                in_table = true;
            }
            html.push_str("<tr>");
            for cell in cells {
                let _ = write!(html, "<{tag}>{}</{tag}>", inline(cell));
            }
            html.push_str("</tr>\n");
        } else if let Some(item) = line.strip_prefix("- ") {
            if !in_list {
                html.push_str("<ul>\n");
                in_list = true;
            }
            let _ = writeln!(html, "<li>{}</li>", inline(item));
        } else if let Some(rest) = line.strip_prefix("![") {
            let (alt, rest) = rest.split_once("](").unwrap_or((rest, ""));
            let file = rest.trim_end_matches(')');
            let path = out.join(file);
            match std::fs::read(&path) {
                Ok(bytes) => {
                    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
                    let _ = writeln!(
                        html,
                        "<img alt=\"{}\" title=\"{}\" src=\"data:image/png;base64,{data}\">",
                        escape(alt),
                        escape(alt)
                    );
                }
                Err(_) => {
                    let _ = writeln!(html, "<p>(missing picture {})</p>", escape(file));
                }
            }
        } else if let Some(level) =
            (1..=3).find(|&l| line.starts_with(&format!("{} ", "#".repeat(l))))
        {
            let _ = writeln!(html, "<h{level}>{}</h{level}>", inline(&line[level + 1..]));
        } else if !line.is_empty() {
            let _ = writeln!(html, "<p>{}</p>", inline(line));
        }
    }
    if in_table {
        html.push_str("</table>\n");
    }
    if in_list {
        html.push_str("</ul>\n");
    }
    html.push_str("</body></html>\n");
    Ok(html)
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown: `code` spans.
fn inline(text: &str) -> String {
    let escaped = escape(text);
    let mut out = String::new();
    for (i, part) in escaped.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out.push_str(part);
        }
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_html_has_every_table_row_and_escapes_text() {
        let md = "# T\n\n| a | b |\n|---|---|\n| <x> | `y` |\n\n- one\n";
        let html = html(md, Path::new("/nonexistent")).unwrap();
        assert!(html.contains("<th>a</th><th>b</th>"), "{html}");
        assert!(
            html.contains("<td>&lt;x&gt;</td><td><code>y</code></td>"),
            "{html}"
        );
        assert!(html.contains("<li>one</li>"));
    }
}
