use super::*;

fn sample() -> Report {
    let mut r = Report::new("Run <x>");
    r.push(Block::Table {
        header: vec!["a|b".into(), "c".into()],
        rows: vec![vec!["1 & 2".into(), "3".into()]],
    })
    .push(Block::Pictures(vec![Picture {
        path: "plots/p.png".into(),
        caption: "progress".into(),
    }]))
    .push(Block::Links(vec![Link {
        path: "exports/design.vxa".into(),
        label: "VXA".into(),
    }]))
    .push(Block::Code {
        language: "toml".into(),
        text: "name = \"<run>\"\n```\n".into(),
    });
    r
}

#[test]
fn html_escapes_text_and_keeps_relative_paths() {
    let html = sample().to_html();
    assert!(html.contains("<title>Run &lt;x&gt;</title>"));
    assert!(html.contains("<td>1 &amp; 2</td>"));
    assert!(html.contains("<img src=\"plots/p.png\""));
    assert!(html.contains("<a href=\"exports/design.vxa\">VXA</a>"));
    assert!(html.contains("name = &quot;&lt;run&gt;&quot;"));
    assert!(!html.contains("<run>"));
}

#[test]
fn markdown_escapes_cell_pipes_and_fences_code_safely() {
    let md = sample().to_markdown();
    assert!(
        md.contains("| a\\|b | c |\n|---|---|\n| 1 & 2 | 3 |\n"),
        "{md}"
    );
    assert!(md.contains("![progress](<plots/p.png>)"));
    assert!(md.contains("- [VXA](<exports/design.vxa>)"));
    // The config holds a three-backtick line, so the fence is four long.
    assert!(md.contains("````toml\nname = \"<run>\"\n```\n````"), "{md}");
}

#[test]
fn referenced_paths_lists_pictures_then_links() {
    assert_eq!(
        sample().referenced_paths(),
        vec!["plots/p.png", "exports/design.vxa"]
    );
}
