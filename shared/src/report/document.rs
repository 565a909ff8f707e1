//! A run report as one document written twice: Markdown, to read in a terminal or on a code forge,
//! and a self-contained HTML page (inline style, no scripts, no network) to open in a browser.
//! Pictures and links are paths relative to the report, so a results folder can be moved or
//! archived whole and its report still shows everything.

use std::fmt::Write;

/// One picture with its caption; `path` is relative to the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    pub path: String,
    pub caption: String,
}

/// One link to a file; `path` is relative to the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    pub path: String,
    pub label: String,
}

/// A block of the report, in reading order.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// A section heading.
    Heading(String),
    /// Plain text (no markup: it is escaped for both outputs).
    Paragraph(String),
    /// A table whose first row is the header; every row has the header's length.
    Table {
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    /// Pictures shown side by side where the page is wide enough.
    Pictures(Vec<Picture>),
    /// A bulleted list of links.
    Links(Vec<Link>),
    /// Preformatted text, e.g. the run's TOML configuration.
    Code { language: String, text: String },
}

/// A titled sequence of blocks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    pub title: String,
    pub blocks: Vec<Block>,
}

impl Report {
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    pub fn push(&mut self, block: Block) -> &mut Self {
        self.blocks.push(block);
        self
    }

    /// Every relative path the report refers to (pictures and links), in order.
    pub fn referenced_paths(&self) -> Vec<&str> {
        self.blocks
            .iter()
            .flat_map(|b| -> Vec<&str> {
                match b {
                    Block::Pictures(p) => p.iter().map(|p| p.path.as_str()).collect(),
                    Block::Links(l) => l.iter().map(|l| l.path.as_str()).collect(),
                    _ => Vec::new(),
                }
            })
            .collect()
    }

    /// GitHub-flavoured Markdown.
    pub fn to_markdown(&self) -> String {
        let mut md = format!("# {}\n", markdown_text(&self.title));
        for block in &self.blocks {
            md.push('\n');
            match block {
                Block::Heading(h) => {
                    let _ = writeln!(md, "## {}", markdown_text(h));
                }
                Block::Paragraph(p) => {
                    let _ = writeln!(md, "{}", markdown_text(p));
                }
                Block::Table { header, rows } => {
                    let row = |cells: &[String]| {
                        let cells: Vec<String> = cells.iter().map(|c| markdown_cell(c)).collect();
                        format!("| {} |\n", cells.join(" | "))
                    };
                    md.push_str(&row(header));
                    md.push_str(&format!("|{}\n", "---|".repeat(header.len())));
                    for r in rows {
                        md.push_str(&row(r));
                    }
                }
                Block::Pictures(pictures) => {
                    for p in pictures {
                        let _ = writeln!(
                            md,
                            "![{}]({})\n\n*{}*\n",
                            markdown_text(&p.caption),
                            markdown_path(&p.path),
                            markdown_text(&p.caption)
                        );
                    }
                }
                Block::Links(links) => {
                    for l in links {
                        let _ = writeln!(
                            md,
                            "- [{}]({})",
                            markdown_text(&l.label),
                            markdown_path(&l.path)
                        );
                    }
                }
                Block::Code { language, text } => {
                    // A fence longer than any backtick run inside keeps the block closed.
                    let longest = text.split(|c| c != '`').map(str::len).max().unwrap_or(0);
                    let fence = "`".repeat(longest.max(2) + 1);
                    let _ = writeln!(md, "{fence}{language}\n{}\n{fence}", text.trim_end());
                }
            }
        }
        md
    }

    /// A complete HTML5 page with an inline style sheet.
    pub fn to_html(&self) -> String {
        let mut html = format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
            html_text(&self.title),
            html_text(&self.title)
        );
        for block in &self.blocks {
            match block {
                Block::Heading(h) => {
                    let _ = writeln!(html, "<h2>{}</h2>", html_text(h));
                }
                Block::Paragraph(p) => {
                    let _ = writeln!(html, "<p>{}</p>", html_text(p));
                }
                Block::Table { header, rows } => {
                    html.push_str("<table>\n<tr>");
                    for h in header {
                        let _ = write!(html, "<th>{}</th>", html_text(h));
                    }
                    html.push_str("</tr>\n");
                    for r in rows {
                        html.push_str("<tr>");
                        for c in r {
                            let _ = write!(html, "<td>{}</td>", html_text(c));
                        }
                        html.push_str("</tr>\n");
                    }
                    html.push_str("</table>\n");
                }
                Block::Pictures(pictures) => {
                    html.push_str("<div class=\"pictures\">\n");
                    for p in pictures {
                        let _ = writeln!(
                            html,
                            "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>",
                            html_text(&p.path),
                            html_text(&p.caption)
                        );
                    }
                    html.push_str("</div>\n");
                }
                Block::Links(links) => {
                    html.push_str("<ul>\n");
                    for l in links {
                        let _ = writeln!(
                            html,
                            "<li><a href=\"{}\">{}</a></li>",
                            html_text(&l.path),
                            html_text(&l.label)
                        );
                    }
                    html.push_str("</ul>\n");
                }
                Block::Code { text, .. } => {
                    let _ = writeln!(html, "<pre>{}</pre>", html_text(text.trim_end()));
                }
            }
        }
        html.push_str("</body>\n</html>\n");
        html
    }
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #bbb;padding:.3em .7em;text-align:left}\
th{background:#eee}pre{background:#f6f6f6;padding:1em;overflow:auto}\
.pictures{display:flex;flex-wrap:wrap;gap:1em}figure{margin:0}img{max-width:520px;height:auto;border:1px solid #ddd}\
figcaption{font-size:90%;color:#555}";

/// Escapes the five characters HTML gives a meaning to (in text and in quoted attributes).
fn html_text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escapes Markdown's inline markup characters so text shows as written.
fn markdown_text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if matches!(
            c,
            '\\' | '`' | '*' | '_' | '[' | ']' | '<' | '>' | '#' | '|'
        ) {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

/// A table cell: escaped text on one line.
fn markdown_cell(s: &str) -> String {
    markdown_text(&s.replace('\n', " "))
}

/// A link target: angle brackets allow spaces; the characters that would end it are encoded.
fn markdown_path(s: &str) -> String {
    format!("<{}>", s.replace('<', "%3C").replace('>', "%3E"))
}

#[cfg(test)]
mod tests;
