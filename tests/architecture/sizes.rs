//! Issue 38's size rules, read from the sources with `syn`: no function of the workspace (its
//! crates' sources, tests, benches and examples, and `tests/`) over 80 lines from its signature
//! to its closing brace, and no file over 600 lines without the words "over 600 lines" and its
//! reason in its first 100 lines.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use proc_macro2::Span;
use syn::visit::Visit;

use super::read_src;

/// Functions over this many lines, signature to closing brace, fail the house rules.
const MAX_FUNCTION_LINES: usize = 80;
/// Files over this many lines must say why at their top.
const MAX_FILE_LINES: usize = 600;

/// Counts the lines of every function with a body: free, in an impl, or a trait's default.
struct FunctionLengths<'a> {
    file: &'a Path,
    long: Vec<String>,
}

impl FunctionLengths<'_> {
    fn check(&mut self, name: &syn::Ident, start: Span, block: &syn::Block) {
        let lines = block.brace_token.span.close().end().line + 1 - start.start().line;
        if lines > MAX_FUNCTION_LINES {
            self.long.push(format!("{}:{}: fn {name}: {lines} lines", self.file.display(), start.start().line));
        }
    }
}

impl<'ast> Visit<'ast> for FunctionLengths<'_> {
    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        self.check(&f.sig.ident, f.sig.fn_token.span, &f.block);
        syn::visit::visit_item_fn(self, f);
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        self.check(&f.sig.ident, f.sig.fn_token.span, &f.block);
        syn::visit::visit_impl_item_fn(self, f);
    }

    fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
        if let Some(block) = &f.default {
            self.check(&f.sig.ident, f.sig.fn_token.span, block);
        }
        syn::visit::visit_trait_item_fn(self, f);
    }
}

/// Every Rust file of the workspace's crates (sources, tests, benches, examples) and of `tests/`,
/// named from the workspace root.
fn workspace_rust_files() -> BTreeMap<PathBuf, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut out = BTreeMap::new();
    let mut folders: Vec<PathBuf> = vec![PathBuf::from("tests")];
    for entry in std::fs::read_dir(root.join("crates")).unwrap() {
        let krate = entry.unwrap().path();
        let name = PathBuf::from("crates").join(krate.file_name().unwrap());
        folders.extend(["src", "tests", "benches", "examples"].map(|f| name.join(f)));
    }
    for folder in folders.into_iter().filter(|f| root.join(f).is_dir()) {
        for (file, text) in read_src(&root.join(&folder)) {
            out.insert(folder.join(file), text);
        }
    }
    out
}

#[test]
fn no_function_over_80_lines_and_no_file_over_600_without_its_reason() {
    let files = workspace_rust_files();
    assert!(files.len() > 100, "read only {} files", files.len());
    let mut problems = Vec::new();
    for (file, text) in &files {
        let parsed = syn::parse_file(text).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let mut lengths = FunctionLengths { file, long: Vec::new() };
        lengths.visit_file(&parsed);
        problems.extend(lengths.long);
        let lines = text.lines().count();
        let top: String = text.lines().take(100).collect::<Vec<_>>().join("\n").to_lowercase();
        if lines > MAX_FILE_LINES && !top.contains(&format!("over {MAX_FILE_LINES} lines")) {
            problems.push(format!(
                "{}: {lines} lines, and no \"over {MAX_FILE_LINES} lines\" reason at its top",
                file.display()
            ));
        }
    }
    assert!(problems.is_empty(), "issue 38's size rules:\n{}", problems.join("\n"));
}
