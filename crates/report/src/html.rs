//! The page: one HTML file, style and script inline, figures as inline SVG; it
//! fetches nothing (opens offline).

use crate::Report;

/// The sections in page order.
pub const SECTIONS: [&str; 9] = [
    "Summary",
    "Trajectory",
    "Errors",
    "Innovations",
    "IMU errors",
    "States",
    "Integrity",
    "Smoother",
    "Tuning",
];

/// Escape text for HTML.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

fn anchor(s: &str) -> String {
    s.to_lowercase().replace(' ', "-")
}

const STYLE: &str = "
body{font-family:sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#1f3b57;color:#fff;padding:12px 20px}
header h1{font-size:18px;margin:0}
nav{position:sticky;top:0;background:#fff;border-bottom:1px solid #ddd;padding:6px 20px;z-index:1}
nav a{margin-right:14px;color:#1f5f99;text-decoration:none;font-size:14px}
main{padding:10px 20px;max-width:1200px}
section{margin-bottom:24px}
h2{font-size:17px;border-bottom:1px solid #ccc;padding-bottom:4px}
figure{margin:10px 0;background:#fff;border:1px solid #e3e3e3;padding:6px;display:inline-block;cursor:zoom-in}
figure.wide{display:block;cursor:zoom-out}
figure.wide svg{width:100%;height:auto}
figcaption{font-size:12px;color:#555;max-width:900px}
table{border-collapse:collapse;font-size:13px;margin:8px 0;background:#fff}
td,th{border:1px solid #ddd;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#f0f0f0}
caption{text-align:left;font-weight:bold;padding:4px 0}
pre{background:#fff;border:1px solid #e3e3e3;padding:8px;font-size:12px;overflow:auto;max-height:480px}
.notes li{font-size:13px;color:#555}
";

/// A click widens a figure to the page width (and back).
const SCRIPT: &str = "
document.querySelectorAll('figure').forEach(function (f) {
  f.addEventListener('click', function () { f.classList.toggle('wide'); });
});
document.body.setAttribute('data-figures', String(document.querySelectorAll('figure svg').length));
";

/// The SVG element of a standalone document (its XML prolog, if any, dropped).
fn inline_svg(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// The whole page.
pub fn page(r: &Report) -> String {
    let mut h = String::with_capacity(r.figures.iter().map(|f| f.svg.len()).sum::<usize>() + 65536);
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    h.push_str(&format!(
        "<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n",
        escape(&r.title)
    ));
    h.push_str(&format!(
        "<header><h1>{}</h1></header>\n<nav>",
        escape(&r.title)
    ));
    let present: Vec<&str> = SECTIONS
        .iter()
        .copied()
        .filter(|s| {
            *s == "Summary"
                || r.figures.iter().any(|f| f.section == *s)
                || r.tables.iter().any(|t| t.section == *s)
        })
        .collect();
    for s in &present {
        h.push_str(&format!("<a href=\"#{}\">{s}</a>", anchor(s)));
    }
    h.push_str("<a href=\"#configuration\">Configuration</a><a href=\"#events\">Events</a></nav>\n<main>\n");
    for s in &present {
        h.push_str(&format!("<section id=\"{}\">\n<h2>{s}</h2>\n", anchor(s)));
        if *s == "Summary" && !r.notes.is_empty() {
            h.push_str("<ul class=\"notes\">");
            for n in &r.notes {
                h.push_str(&format!("<li>{}</li>", escape(n)));
            }
            h.push_str("</ul>\n");
        }
        for t in r.tables.iter().filter(|t| t.section == *s) {
            h.push_str(&format!(
                "<table>\n<caption>{}</caption>\n",
                escape(&t.caption)
            ));
            if t.header.iter().any(|x| !x.is_empty()) {
                h.push_str("<tr>");
                for c in &t.header {
                    h.push_str(&format!("<th>{}</th>", escape(c)));
                }
                h.push_str("</tr>\n");
            }
            for row in &t.rows {
                h.push_str("<tr>");
                for c in row {
                    h.push_str(&format!("<td>{}</td>", escape(c)));
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n");
        }
        for f in r.figures.iter().filter(|f| f.section == *s) {
            h.push_str(&format!("<figure id=\"fig-{}\">\n", escape(&f.name)));
            h.push_str(inline_svg(&f.svg));
            h.push_str(&format!(
                "\n<figcaption>{}</figcaption>\n</figure>\n",
                escape(&f.caption)
            ));
        }
        h.push_str("</section>\n");
    }
    h.push_str("<section id=\"configuration\">\n<h2>Configuration</h2>\n");
    match &r.config {
        Some(c) => h.push_str(&format!("<pre>{}</pre>\n", escape(c))),
        None => h.push_str("<p>No config.toml in the run directory (runs before this version did not write it).</p>\n"),
    }
    h.push_str("</section>\n<section id=\"events\">\n<h2>Events</h2>\n");
    const MAX_EVENTS: usize = 2000;
    let shown: Vec<&str> = r
        .events
        .iter()
        .take(MAX_EVENTS)
        .map(String::as_str)
        .collect();
    h.push_str(&format!("<pre>{}</pre>\n", escape(&shown.join("\n"))));
    if r.events.len() > MAX_EVENTS {
        h.push_str(&format!(
            "<p>{} more lines in events.log.</p>\n",
            r.events.len() - MAX_EVENTS
        ));
    }
    h.push_str("</section>\n</main>\n");
    h.push_str(&format!("<script>{SCRIPT}</script>\n</body>\n</html>\n"));
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
    }
}
