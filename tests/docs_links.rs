//! The README and the book under `docs/book/` (issue 38): every relative link of `README.md` and
//! `docs/**/*.md` reaches a file, and every `#anchor` into a markdown file names one of its
//! headings (GitHub's and mdBook's slugs, which agree on our headings); the README stays a front
//! door of at most 300 lines; `SUMMARY.md` lists every chapter; and every shell example of the
//! README and the book runs as written on a fresh clone: this build's `skinkit` first on `PATH`,
//! in a folder holding a copy of the repository's `samples/` and `calibration/`.
//!
//! A shell block that cannot run here (it needs a cluster, a display, files the repository does
//! not hold, or minutes) is fenced as ```` ```sh no-run ```` (GitHub and mdBook take the first
//! word as the language and ignore the rest), with its reason in a comment on the line before
//! it: `<!-- no-run: ... -->`. A tag without a reason fails.

use pulldown_cmark::{CodeBlockKind, Event, Options, Parser, Tag, TagEnd};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn book_src() -> PathBuf {
    root().join("docs/book/src")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn parser(text: &str) -> Parser<'_> {
    Parser::new_ext(text, Options::ENABLE_TABLES | Options::ENABLE_STRIKETHROUGH)
}

/// `README.md` and every `.md` file under `docs/`, the book's build folder left out. Linked
/// folders are not entered (the book's `src/accuracy` is `docs/accuracy`); linked files are
/// read where they are linked, since the book renders them there.
fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for path in entries {
            let linked = path.symlink_metadata().unwrap().file_type().is_symlink();
            if path.is_dir() && !linked && path.file_name() != Some("build".as_ref()) {
                walk(&path, out);
            } else if path.extension() == Some("md".as_ref()) {
                out.push(path);
            }
        }
    }
    let mut files = vec![root().join("README.md")];
    walk(&root().join("docs"), &mut files);
    files
}

/// A heading's anchor as GitHub and mdBook make it: lower case, letters, digits, `-` and `_`
/// kept, spaces to `-`, everything else dropped.
fn slug(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| match c {
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c.to_lowercase().next().unwrap_or(c)),
            c if c.is_whitespace() => Some('-'),
            _ => None,
        })
        .collect()
}

/// The anchors of a markdown text's headings; a repeated one gets `-1`, `-2`, ... as on GitHub.
fn anchors(text: &str) -> Vec<String> {
    let (mut out, mut seen, mut heading) = (Vec::new(), HashMap::<String, usize>::new(), None::<String>);
    for event in parser(text) {
        match event {
            Event::Start(Tag::Heading { .. }) => heading = Some(String::new()),
            Event::Text(t) | Event::Code(t) => heading.iter_mut().for_each(|h| h.push_str(&t)),
            Event::End(TagEnd::Heading(_)) => {
                let base = slug(heading.take().unwrap_or_default().trim());
                let n = seen.entry(base.clone()).or_insert(0);
                out.push(if *n == 0 { base.clone() } else { format!("{base}-{n}") });
                *n += 1;
            }
            _ => {}
        }
    }
    out
}

/// Every link and image destination of a markdown text, in order.
fn destinations(text: &str) -> Vec<String> {
    parser(text)
        .filter_map(|event| match event {
            Event::Start(Tag::Link { dest_url, .. } | Tag::Image { dest_url, .. }) => Some(dest_url.into_string()),
            _ => None,
        })
        .collect()
}

/// What is wrong with the relative links of `text`, read as the file `file`: targets that do
/// not exist and anchors no heading of a markdown target has. Web addresses are not followed.
fn broken_links(file: &Path, text: &str) -> Vec<String> {
    let mut broken = Vec::new();
    for dest in destinations(text) {
        if dest.contains("://") || dest.starts_with("mailto:") {
            continue;
        }
        let (path, anchor) = dest.split_once('#').unwrap_or((&dest, ""));
        let target = if path.is_empty() { file.to_owned() } else { file.parent().unwrap().join(path) };
        if !target.exists() {
            broken.push(format!("{dest}: no file {}", target.display()));
        } else if !anchor.is_empty() && target.extension() == Some("md".as_ref()) {
            let target_text = if path.is_empty() { text.to_owned() } else { read(&target) };
            if !anchors(&target_text).iter().any(|a| a == anchor) {
                broken.push(format!("{dest}: no heading #{anchor} in {}", target.display()));
            }
        }
    }
    broken
}

#[test]
fn every_relative_link_of_the_readme_and_the_book_reaches_its_target() {
    let files = markdown_files();
    assert!(files.len() > 20, "only {} markdown files found", files.len());
    let broken: Vec<String> = files
        .iter()
        .flat_map(|f| broken_links(f, &read(f)).into_iter().map(move |b| format!("{}: {b}", f.display())))
        .collect();
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_link_check_finds_a_missing_file_and_a_missing_heading() {
    let readme = root().join("README.md");
    let text = "# A title\n\n[fine](#a-title) [fine](docs/references.md) [fine](README.md#quick-start)\n\
                [gone](docs/no-such-chapter.md) [gone](#no-such-heading) ![gone](docs/missing.png)\n\
                [gone](README.md#no-such-section) [web](https://example.org/none)\n";
    let broken = broken_links(&readme, text);
    assert_eq!(broken.len(), 4, "{broken:#?}");
    for (found, dest) in broken.iter().zip(["docs/no-such-chapter.md", "#no-such-heading", "docs/missing.png"]) {
        assert!(found.starts_with(dest), "{found}");
    }
    assert!(broken[3].contains("no heading #no-such-section"), "{}", broken[3]);
}

#[test]
fn headings_get_the_anchors_github_and_mdbook_give_them() {
    let text = "# Every stage: accuracy against time\n## `skinkit batch`, sharded\n## Notes\n## Notes\n";
    assert_eq!(anchors(text), ["every-stage-accuracy-against-time", "skinkit-batch-sharded", "notes", "notes-1"]);
}

#[test]
fn the_readme_is_a_front_door_of_at_most_300_lines() {
    let lines = read(&root().join("README.md")).lines().count();
    assert!(lines <= 300, "README.md has {lines} lines; move detail into a chapter of docs/book/src/");
}

/// The chapters of `SUMMARY.md`, in its order.
fn summary_chapters() -> Vec<String> {
    destinations(&read(&book_src().join("SUMMARY.md")))
}

#[test]
fn the_summary_lists_every_chapter_file() {
    let listed = summary_chapters();
    let mut files: Vec<String> = std::fs::read_dir(book_src())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".md") && n != "SUMMARY.md")
        .collect();
    files.sort();
    let missing: Vec<&String> = files.iter().filter(|f| !listed.contains(f)).collect();
    assert!(missing.is_empty(), "docs/book/src/SUMMARY.md does not list {missing:?}");
}

/// A fenced shell block: where it starts, its code, and whether it is tagged `no-run`.
struct Block {
    line: usize,
    code: String,
    no_run: bool,
}

/// The `sh`, `bash`, `shell` and `console` blocks of a markdown text (`console` lines that do
/// not start with `$ ` are output). A `no-run` block without its reason on the line before it
/// is an error.
fn shell_blocks(file: &Path, text: &str) -> Vec<Block> {
    let line_of = |offset: usize| text[..offset].lines().count() + 1;
    let mut blocks = Vec::new();
    let mut current: Option<(Block, bool)> = None;
    for (event, range) in parser(text).into_offset_iter() {
        match event {
            Event::Start(Tag::CodeBlock(CodeBlockKind::Fenced(info))) => {
                let mut words = info.split([' ', ',', '\t']).filter(|w| !w.is_empty());
                let language = words.next().unwrap_or("");
                if !["sh", "bash", "shell", "console"].contains(&language) {
                    continue;
                }
                let no_run = words.any(|w| w == "no-run");
                let line = line_of(range.start);
                if no_run {
                    let before = text[..range.start].trim_end().lines().last().unwrap_or("").trim_start();
                    assert!(
                        before.starts_with("<!-- no-run: ") && before.ends_with("-->"),
                        "{}:{line}: a no-run block needs its reason on the line before it, `<!-- no-run: ... -->`",
                        file.display()
                    );
                }
                current = Some((Block { line, code: String::new(), no_run }, language == "console"));
            }
            Event::Text(t) => {
                if let Some((block, _)) = current.as_mut() {
                    block.code.push_str(&t);
                }
            }
            Event::End(TagEnd::CodeBlock) => {
                if let Some((mut block, console)) = current.take() {
                    if console {
                        block.code =
                            block.code.lines().filter_map(|l| l.strip_prefix("$ ")).collect::<Vec<_>>().join("\n");
                    }
                    blocks.push(block);
                }
            }
            _ => {}
        }
    }
    blocks
}

/// Copies a folder of the repository, following links to files.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_tree(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// A fresh clone's inputs, as far as the examples read them: copies, so that an example that
/// writes (`skinkit samples --out ...`) cannot touch the repository.
fn fresh_clone() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for folder in ["samples", "calibration"] {
        copy_tree(&root().join(folder), &dir.path().join(folder));
    }
    dir
}

/// Runs every runnable shell block of `files` in order, each with `bash -e -o pipefail`, in one
/// fresh folder (a later block may read what an earlier one wrote, as a reader would have it),
/// and prints each block's time. Returns how many ran.
fn run_examples(files: &[PathBuf]) -> usize {
    let clone = fresh_clone();
    let bin = Path::new(env!("CARGO_BIN_EXE_skinkit")).parent().unwrap().to_owned();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let (start, mut ran) = (Instant::now(), 0);
    for file in files {
        let name = file.strip_prefix(root()).unwrap_or(file).display().to_string();
        for block in shell_blocks(file, &read(file)).into_iter().filter(|b| !b.no_run) {
            let t = Instant::now();
            let o = Command::new("bash")
                .args(["-e", "-o", "pipefail", "-c", &block.code])
                .current_dir(clone.path())
                .env("PATH", &path)
                .output()
                .expect("bash runs");
            assert!(
                o.status.success(),
                "{name}:{}: the example failed ({}):\n{}\nstdout:\n{}\nstderr:\n{}",
                block.line,
                o.status,
                block.code,
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            );
            eprintln!("{name}:{}: {:.1} s", block.line, t.elapsed().as_secs_f64());
            ran += 1;
        }
    }
    eprintln!("{ran} blocks in {:.1} s", start.elapsed().as_secs_f64());
    ran
}

#[test]
fn the_readme_examples_run_as_written() {
    assert!(run_examples(&[root().join("README.md")]) >= 1, "the README shows no runnable example");
}

#[test]
fn the_book_examples_run_as_written() {
    let chapters: Vec<PathBuf> = summary_chapters().iter().map(|c| book_src().join(c)).collect();
    assert!(run_examples(&chapters) >= 9, "the book shows fewer runnable examples than it did (9)");
}
