//! The circle finder on tiny in-memory trees.

use super::*;

fn tree(files: &[(&str, &str)]) -> BTreeMap<PathBuf, String> {
    files.iter().map(|(p, t)| (PathBuf::from(p), t.to_string())).collect()
}

fn names(files: &[(&str, &str)]) -> Vec<Vec<String>> {
    let found = circles(&tree(files)).unwrap();
    found.iter().map(|c| c.members.iter().map(|m| display(m)).collect()).collect()
}

#[test]
fn a_two_module_cycle_is_found_with_its_lines() {
    let files = tree(&[
        ("lib.rs", "mod a;\nmod b;\nmod c;\n"),
        ("a.rs", "use crate::b::B;\npub struct A;\n"),
        ("b.rs", "pub struct B;\nfn f() -> super::a::A { super::a::A }\n"),
        ("c.rs", "use crate::a::A;\n"),
    ]);
    let found = circles(&files).unwrap();
    assert_eq!(found.len(), 1);
    let c = &found[0];
    assert_eq!(c.members, [vec!["a".to_string()], vec!["b".to_string()]]);
    let lines: Vec<_> = c.edges.iter().map(|e| (e.evidence.file.clone(), e.evidence.line)).collect();
    assert_eq!(lines, [(PathBuf::from("a.rs"), 1), (PathBuf::from("b.rs"), 2)]);
    assert_eq!(c.edges[0].evidence.text, "use crate::b::B;");
}

#[test]
fn a_parent_re_exporting_its_child_is_not_a_circle() {
    let files = &[
        ("lib.rs", "pub mod a;\npub use a::Thing;\npub fn helper() {}\n"),
        ("a.rs", "pub struct Thing;\nfn f() { super::helper(); crate::Thing; }\npub mod inner;\n"),
        ("a/inner.rs", "use super::Thing;\nuse crate::a;\n"),
    ];
    assert!(names(files).is_empty());
}

#[test]
fn grouped_imports_and_inline_paths_make_edges() {
    let files = &[
        ("lib.rs", "mod a;\nmod b;\nmod c;\nmod d;\n"),
        ("a.rs", "use crate::{b::{self, B}, c::C as Sea};\n"),
        ("b.rs", "pub struct B;\nfn f() { let _ = crate::d::g(); }\n"),
        ("c.rs", "pub struct C;\n"),
        ("d.rs", "pub fn g() { assert!(crate::a::ok()); }\n"),
    ];
    assert_eq!(names(files), [vec!["crate::a", "crate::b", "crate::d"]]);
}

#[test]
fn comments_strings_and_outside_paths_are_not_edges() {
    let files = &[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "use crate::b::B;\n"),
        (
            "b.rs",
            "// use crate::a::A;\n/// [crate::a::A]\npub struct B;\nconst S: &str = \"crate::a::A\";\n\
             fn f() { std::mem::drop(Self::x); ::a::y(); }\n",
        ),
    ];
    assert!(names(files).is_empty());
}

#[test]
fn re_exports_and_globs_lead_to_where_an_item_lives() {
    let files = &[
        ("lib.rs", "mod a;\nmod b;\npub use b::Thing;\n"),
        ("a.rs", "use crate::Thing;\npub fn f() {}\n"),
        ("b/mod.rs", "pub struct Thing;\n#[cfg(test)]\nmod tests;\n"),
        ("b/tests.rs", "use super::super::*;\nfn t() { a::f(); }\n"),
    ];
    assert_eq!(names(files), [vec!["crate::a", "crate::b"]]);
}

#[test]
fn circles_are_found_at_every_level() {
    let files = &[
        ("lib.rs", "pub mod solve;\n"),
        ("solve.rs", "mod fit;\nmod plan { pub struct P; pub fn f() -> super::fit::F { todo!() } }\n"),
        ("solve/fit.rs", "pub struct F(super::plan::P);\n"),
    ];
    assert_eq!(names(files), [vec!["crate::solve::fit", "crate::solve::plan"]]);
}

#[test]
fn a_missing_module_file_is_an_error() {
    let err = circles(&tree(&[("lib.rs", "mod gone;\n")])).unwrap_err();
    assert!(err.contains("gone.rs"), "{err}");
}
