//! Every document the project cites is in the repository (the rules are in
//! docs/interfaces.md section 10):
//!
//! * a capitalised Markdown document (`NAME.md`, the convention of top-level
//!   documents such as the README) named anywhere is a tracked file;
//! * a relative path that climbs (`../...`) in prose (comments, Markdown,
//!   TOML, scripts) lands inside the repository on something that exists;
//! * a citation `docs/<name>.md section N` names a section that exists.
//!
//! The rules name no document of their own: anything outside the
//! repository fails them, whatever it is called.

use std::path::{Component, Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The repository's tracked files with their text (binary files skipped).
fn tracked_files() -> Vec<(String, String)> {
    let out = Command::new("git")
        .arg("ls-files")
        .current_dir(root())
        .output()
        .expect("git is needed to list the tracked files");
    assert!(out.status.success(), "git ls-files failed");
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|f| {
            let text = std::fs::read_to_string(root().join(f)).ok()?;
            Some((f.to_string(), text))
        })
        .collect()
}

fn path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || "_-./".contains(c)
}

/// The prose of a line: the comment of a Rust line, the whole line of
/// any other file (Markdown, TOML, scripts).
fn prose<'a>(file: &str, line: &'a str) -> &'a str {
    if file.ends_with(".rs") {
        line.find("//").map_or("", |i| &line[i..])
    } else {
        line
    }
}

/// `a/b/../c` -> `a/c`; None if it climbs above the start.
fn normalise(p: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    Some(out)
}

/// What in `text` (of `file`, a path relative to the root) refers to a
/// document outside the repository, as `file:line: token`.
fn outside_references(file: &str, text: &str, tracked: &[String]) -> Vec<String> {
    let dir = Path::new(file).parent().unwrap_or(Path::new(""));
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        // capitalised Markdown documents must be tracked files
        let mut rest = line;
        while let Some(i) = rest.find(".md") {
            let start = rest[..i]
                .rfind(|c: char| !path_char(c))
                .map_or(0, |j| j + 1);
            let token = &rest[start..i + 3];
            let name = token.rsplit('/').next().unwrap_or(token);
            let stem = &name[..name.len() - 3];
            let capital = stem.chars().any(|c| c.is_ascii_uppercase())
                && !stem.chars().any(|c| c.is_ascii_lowercase());
            if capital && !tracked.iter().any(|t| t.rsplit('/').next() == Some(name)) {
                found.push(format!("{file}:{}: {token}", n + 1));
            }
            rest = &rest[i + 3..];
        }
        // climbing relative paths in prose must land on something inside
        let text = prose(file, line);
        let mut rest = text;
        while let Some(i) = rest.find("../") {
            let before = rest[..i].chars().last();
            if before.is_some_and(path_char) {
                rest = &rest[i + 3..];
                continue;
            }
            let end = rest[i..]
                .find(|c: char| !path_char(c))
                .map_or(rest.len(), |e| i + e);
            let token = rest[i..end].trim_end_matches(['.', '/']);
            let inside = normalise(&dir.join(token)).filter(|p| root().join(p).exists());
            if inside.is_none() {
                found.push(format!("{file}:{}: {token}", n + 1));
            }
            rest = &rest[end.max(i + 3)..];
        }
    }
    found
}

/// Every `docs/<name>.md section N` (or `sections N-M`) cited in `text`.
fn citations(text: &str) -> Vec<(String, u32)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("docs/") {
        rest = &rest[i + 5..];
        let Some(end) = rest.find(".md") else { break };
        let name = &rest[..end];
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        let after = rest[end + 3..].trim_start_matches(['`', ' ']);
        let nums = after
            .strip_prefix("sections ")
            .or_else(|| after.strip_prefix("section "));
        if let Some(nums) = nums {
            let digits: String = nums
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '-')
                .collect();
            for part in digits.split('-').filter(|p| !p.is_empty()) {
                out.push((format!("docs/{name}.md"), part.parse().unwrap()));
            }
        }
    }
    out
}

#[test]
fn no_tracked_file_refers_to_a_document_outside_the_repository() {
    let files = tracked_files();
    let names: Vec<String> = files.iter().map(|(f, _)| f.clone()).collect();
    // this file's own examples name made-up documents on purpose
    let me = "tests/no_external_refs.rs";
    let found: Vec<String> = files
        .iter()
        .filter(|(f, _)| f != me)
        .flat_map(|(f, t)| outside_references(f, t, &names))
        .collect();
    assert!(
        found.is_empty(),
        "outside references:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_rules_find_outside_references_and_pass_inside_ones() {
    let tracked = vec![
        "README.md".to_string(),
        "designs/seed_pump.toml".to_string(),
    ];
    // an untracked capitalised document, a path out of the repository, a
    // path to nothing
    let text = "see NOTES.md\nand ../../elsewhere/a.txt\n# ../nothing/here.toml\n";
    assert_eq!(
        outside_references("docs/x.md", text, &tracked),
        vec![
            "docs/x.md:1: NOTES.md".to_string(),
            "docs/x.md:2: ../../elsewhere/a.txt".to_string(),
            "docs/x.md:3: ../nothing/here.toml".to_string(),
        ]
    );
    // in a Rust file, a comment is prose
    assert_eq!(
        outside_references("src/x.rs", "//! see ../../elsewhere\n", &tracked),
        vec!["src/x.rs:1: ../../elsewhere".to_string()]
    );
    // the README, a lower-case output name, a path to a tracked file, and a
    // path in code rather than prose pass
    let ok = "see README.md and report.md\n// ../designs/seed_pump.toml\nlet p = \"../x\";\n";
    assert!(outside_references("src/x.rs", ok, &tracked).is_empty());
}

#[test]
fn every_cited_section_of_a_project_document_exists() {
    let files = tracked_files();
    let mut missing = Vec::new();
    let mut checked = 0;
    for (file, text) in &files {
        for (doc, n) in citations(text) {
            let Some((_, body)) = files.iter().find(|(f, _)| *f == doc) else {
                missing.push(format!("{file}: {doc} does not exist"));
                continue;
            };
            checked += 1;
            if !body.lines().any(|l| l.starts_with(&format!("## {n}. "))) {
                missing.push(format!("{file}: {doc} has no section {n}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "dangling citations:\n{}",
        missing.join("\n")
    );
    assert!(
        checked > 20,
        "only {checked} citations found: the parser missed them"
    );
    // and the parser reads ranges
    assert_eq!(
        citations("see docs/model.md sections 5-6 and `docs/interfaces.md` section 4"),
        vec![
            ("docs/model.md".to_string(), 5),
            ("docs/model.md".to_string(), 6),
            ("docs/interfaces.md".to_string(), 4)
        ]
    );
}
