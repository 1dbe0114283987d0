//! Nothing the repository ships refers to a document outside it, and every
//! citation of a project document (`docs/<name>.md section N`) names a
//! section that exists there, so no reference dangles.

use std::path::Path;
use std::process::Command;

/// What an outside reference looks like: the names of the documents the
/// project was specified in, and paths out of the repository.
const OUTSIDE: [&str; 8] = [
    "MODEL.md",
    "INTERFACES.md",
    "STYLE.md",
    "FMI-NOTES.md",
    "shared/spec",
    "shared/seed",
    "../shared",
    "000_45abc730c918abf3",
];

/// The repository's tracked files with their text (binary files skipped).
fn tracked_files() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("git")
        .arg("ls-files")
        .current_dir(root)
        .output()
        .expect("git is needed to list the tracked files");
    assert!(out.status.success(), "git ls-files failed");
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|f| {
            let text = std::fs::read_to_string(root.join(f)).ok()?;
            Some((f.to_string(), text))
        })
        .collect()
}

/// `(file, line, offending text)` for every outside reference in `text`.
fn outside_references(file: &str, text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for name in OUTSIDE {
            if line.contains(name) {
                found.push(format!("{file}:{}: {name}", n + 1));
            }
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
    // this file names the outside documents in order to find them
    let me = "tests/no_external_refs.rs";
    let found: Vec<String> = tracked_files()
        .iter()
        .filter(|(f, _)| f != me)
        .flat_map(|(f, t)| outside_references(f, t))
        .collect();
    assert!(
        found.is_empty(),
        "outside references:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_check_finds_an_outside_reference() {
    let text = "ok\n//! see MODEL.md section 4\n";
    assert_eq!(
        outside_references("x.rs", text),
        vec!["x.rs:2: MODEL.md".to_string()]
    );
    assert!(outside_references("x.rs", "docs/model.md section 4").is_empty());
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
