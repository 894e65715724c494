//! The documents can be navigated: README.md stays short (at most 25 KB) and, like the guide
//! (docs/GUIDE.md), opens with a table of contents that lists every section; every relative
//! link in README.md, docs/GUIDE.md and ARCHITECTURE.md reaches a file, and every `#anchor` a
//! heading of its document.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The lines of `text` outside fenced code blocks (a shell comment in a block is no heading).
fn prose(text: &str) -> Vec<&str> {
    let mut fenced = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced {
            lines.push(line);
        }
    }
    lines
}

/// The headings of a Markdown text: (level, text).
fn headings(text: &str) -> Vec<(usize, String)> {
    prose(text)
        .into_iter()
        .filter_map(|line| {
            let level = line.chars().take_while(|&c| c == '#').count();
            let title = line[level..].strip_prefix(' ')?;
            (level > 0).then(|| (level, title.trim().to_owned()))
        })
        .collect()
}

/// The anchor GitHub gives a heading: lower case, punctuation dropped (letters, digits, `-`
/// and `_` kept), spaces turned into hyphens.
fn slug(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor of a document's headings (a repeated heading's second anchor gets `-1`).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for (_, title) in headings(text) {
        let base = slug(&title);
        let mut anchor = base.clone();
        let mut n = 0;
        while found.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        found.insert(anchor);
    }
    found
}

/// The targets of the Markdown links `[text](target)` in the prose of `text`.
fn links(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for line in prose(text) {
        for (i, _) in line.match_indices("](") {
            let rest = &line[i + 2..];
            if let Some(end) = rest.find(')') {
                found.push(rest[..end].to_owned());
            }
        }
    }
    found
}

/// The `(#anchor)` links under the document's `## Contents` heading.
fn contents(text: &str) -> Vec<String> {
    let lines = prose(text);
    let start = lines.iter().position(|l| *l == "## Contents").expect("a `## Contents` section");
    lines[start + 1..].iter().take_while(|l| !l.starts_with('#')).flat_map(|l| links(l)).collect()
}

/// The table of contents of `doc` comes before its first section, lists every heading of the
/// given levels, and each of its links reaches a heading.
fn check_contents(doc: &str, levels: &[usize]) {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    let toc = contents(&text);
    let all = anchors(&text);
    for link in &toc {
        let anchor =
            link.strip_prefix('#').unwrap_or_else(|| panic!("{doc}: contents link {link} is not an anchor"));
        assert!(all.contains(anchor), "{doc}: contents link {link} reaches no heading; anchors: {all:?}");
    }
    let heads = headings(&text);
    let first_section = heads.iter().position(|(level, _)| *level == 2).unwrap();
    assert_eq!(heads[first_section].1, "Contents", "{doc}: the contents come first");
    for (level, title) in &heads {
        if levels.contains(level) && title != "Contents" {
            let link = format!("#{}", slug(title));
            assert!(toc.contains(&link), "{doc}: the contents leave out the section {title:?} ({link})");
        }
    }
    assert!(toc.len() >= 4, "{doc}: only {} contents links", toc.len());
}

#[test]
fn readme_is_at_most_25_kb_and_opens_with_its_contents() {
    let size = std::fs::metadata(root().join("README.md")).unwrap().len();
    assert!(
        size <= 25 * 1024,
        "README.md is {size} bytes, more than 25 KB: move the detail to docs/GUIDE.md"
    );
    check_contents("README.md", &[2]);
}

#[test]
fn the_guide_opens_with_contents_listing_every_section() {
    check_contents("docs/GUIDE.md", &[2, 3]);
}

/// Every relative link of the three documents reaches a file, and an anchor a heading there.
#[test]
fn document_links_resolve() {
    let mut checked = 0;
    for doc in ["README.md", "docs/GUIDE.md", "ARCHITECTURE.md"] {
        let path = root().join(doc);
        let text = std::fs::read_to_string(&path).unwrap();
        for link in links(&text) {
            if link.starts_with("http://") || link.starts_with("https://") {
                continue;
            }
            let (file, anchor) = link.split_once('#').unwrap_or((&link, ""));
            let target = if file.is_empty() { path.clone() } else { path.parent().unwrap().join(file) };
            assert!(target.exists(), "{doc} links to {link}, which does not exist");
            if !anchor.is_empty() {
                let target_text = std::fs::read_to_string(&target).unwrap();
                assert!(anchors(&target_text).contains(anchor), "{doc} links to {link}: no such heading");
            }
            checked += 1;
        }
    }
    assert!(checked >= 20, "only {checked} links found");
}

/// The checks can fail: a link to a missing heading is no anchor, and GitHub's rule is the
/// one implemented (punctuation dropped, a `--flag` keeping its hyphens).
#[test]
fn the_anchor_rule_is_githubs() {
    assert_eq!(
        slug("Long runs: `--checkpoint` and `pendula resume`"),
        "long-runs---checkpoint-and-pendula-resume"
    );
    assert_eq!(
        slug("Outputs: whole or not at all, never destroyed"),
        "outputs-whole-or-not-at-all-never-destroyed"
    );
    let text = "# T\n\n## Contents\n\n- [A](#a)\n\n## A\n\n```sh\n# not a heading\n```\n\n## A\n";
    assert_eq!(anchors(text), ["t", "contents", "a", "a-1"].map(String::from).into());
    assert_eq!(contents(text), ["#a"]);
}
