//! The house rules of issue 38 that read the libraries' sources rather than run them: no module
//! circles inside a crate, nothing outside the renderer behind its front door, no function over
//! 80 lines and no file over 600 without its reason.
//!
//! At every level of a crate's module tree the sibling modules are the nodes of a graph (a node
//! stands for the module and all its descendants) with an edge `a -> b` when code anywhere in
//! `a`'s subtree names something in `b`'s: through `crate::`, `super::` or `self::` paths, a child
//! module's name, a `use` group (`crate::{a, b::c}`), a path written inline without `use`, or a
//! path inside a macro call. A name the parent re-exports (`pub use b::Thing;` in the parent and
//! `use super::Thing;` in `a`) counts as naming `b`, since that is where it lives. A circle is a
//! strongly connected component of more than one node: modules that cannot be understood, tested
//! or moved one without the other.
//!
//! Sources are parsed with `syn`, so comments, strings and doc links never count. Not followed: an
//! item a glob import brings in that its module only re-exports through another glob, and
//! `#[path]` attributes on inline modules.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use proc_macro2::{Span, TokenStream, TokenTree};
use syn::visit::Visit;

/// A module's path from the crate root: `["solve", "plan"]` is `crate::solve::plan`.
pub type ModPath = Vec<String>;

/// Where one module names another: the file (relative to `src/`), its line and what it says.
#[derive(Clone, Debug)]
pub struct Evidence {
    pub file: PathBuf,
    pub line: usize,
    pub text: String,
    /// A `use` declaration rather than a path inline; the report prefers these.
    pub is_use: bool,
}

/// One edge of a circle with the first place that makes it (a `use` when there is one).
#[derive(Debug)]
pub struct Edge {
    pub from: ModPath,
    pub to: ModPath,
    pub evidence: Evidence,
}

/// Sibling modules that depend on each other, with the edges between them.
#[derive(Debug)]
pub struct Circle {
    pub members: Vec<ModPath>,
    pub edges: Vec<Edge>,
}

/// `crate::a::b` for `["a", "b"]`.
pub fn display(path: &[String]) -> String {
    std::iter::once("crate").chain(path.iter().map(String::as_str)).collect::<Vec<_>>().join("::")
}

impl Circle {
    /// The members on one line, then each edge with its file (under `src`), line and text.
    pub fn report(&self, src: &str) -> String {
        let names: Vec<_> = self.members.iter().map(|m| display(m)).collect();
        let mut out = format!("circle: {}\n", names.join(", "));
        for e in &self.edges {
            let ev = &e.evidence;
            let (from, to, file) = (display(&e.from), display(&e.to), ev.file.display());
            out += &format!("  {from} -> {to}: {src}/{file}:{}: {}\n", ev.line, ev.text);
        }
        out
    }
}

/// Every `.rs` file under `src`, by path relative to it.
pub fn read_src(src: &Path) -> BTreeMap<PathBuf, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, String>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(root, &path, out);
            } else if path.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                out.insert(path.strip_prefix(root).unwrap().to_path_buf(), text);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(src, src, &mut out);
    out
}

/// The module circles of the crate whose `src/` files are `files` (relative paths, `lib.rs` or
/// `main.rs` the root), at every level of its module tree, in module order.
///
/// # Errors
/// A file that does not parse, or a `mod x;` with neither `x.rs` nor `x/mod.rs`.
pub fn circles(files: &BTreeMap<PathBuf, String>) -> Result<Vec<Circle>, String> {
    let krate = Crate::load(files)?;
    let mut levels: BTreeMap<ModPath, Vec<Edge>> = BTreeMap::new();
    for r in &krate.references {
        if let Some((parent, edge)) = krate.edge(r) {
            levels.entry(parent).or_default().push(edge);
        }
    }
    let mut out = Vec::new();
    for (parent, module) in &krate.modules {
        let edges = levels.remove(parent).unwrap_or_default();
        out.extend(level_circles(parent, &module.children, edges));
    }
    Ok(out)
}

/// The strongly connected components of more than one node among `parent`'s children.
fn level_circles(parent: &[String], children: &BTreeSet<String>, edges: Vec<Edge>) -> Vec<Circle> {
    let name = |m: &ModPath| m[parent.len()].clone();
    let mut next: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for e in &edges {
        next.entry(name(&e.from)).or_default().insert(name(&e.to));
    }
    let reach = |from: &String| {
        let (mut seen, mut stack) = (BTreeSet::new(), vec![from.clone()]);
        while let Some(n) = stack.pop() {
            for m in next.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&String, BTreeSet<String>> = children.iter().map(|c| (c, reach(c))).collect();
    let mut placed = BTreeSet::new();
    let mut out = Vec::new();
    for c in children {
        if placed.contains(c) {
            continue;
        }
        let component: BTreeSet<String> = children
            .iter()
            .filter(|d| *d == c || (reaches[c].contains(*d) && reaches[d].contains(c)))
            .cloned()
            .collect();
        placed.extend(component.iter().cloned());
        if component.len() > 1 {
            out.push(circle(parent, &component, &edges));
        }
    }
    out
}

/// The circle of `component`, one edge per ordered pair (a `use` first, else the first seen).
fn circle(parent: &[String], component: &BTreeSet<String>, edges: &[Edge]) -> Circle {
    let path = |n: &String| [parent, std::slice::from_ref(n)].concat();
    let mut chosen: BTreeMap<(String, String), &Edge> = BTreeMap::new();
    for e in edges {
        let (a, b) = (e.from[parent.len()].clone(), e.to[parent.len()].clone());
        if !(component.contains(&a) && component.contains(&b)) {
            continue;
        }
        let slot = chosen.entry((a, b)).or_insert(e);
        if e.evidence.is_use && !slot.evidence.is_use {
            *slot = e;
        }
    }
    let edges = chosen
        .into_iter()
        .map(|((a, b), e)| Edge { from: path(&a), to: path(&b), evidence: e.evidence.clone() })
        .collect();
    Circle { members: component.iter().map(path).collect(), edges }
}

/// What the graph needs of one module: its children, the names it defines and imports.
#[derive(Default)]
struct Module {
    children: BTreeSet<String>,
    items: BTreeSet<String>,
    /// Imported name -> the path as written (relative to this module).
    imports: BTreeMap<String, Vec<String>>,
    globs: Vec<Vec<String>>,
}

/// A path as written in module `from`.
struct Reference {
    from: ModPath,
    path: Vec<String>,
    evidence: Evidence,
}

#[derive(Default)]
struct Crate {
    modules: BTreeMap<ModPath, Module>,
    references: Vec<Reference>,
}

/// How deep re-exports are followed before a path is taken as it stands (a guard against loops).
const MAX_HOPS: usize = 16;

impl Crate {
    fn load(files: &BTreeMap<PathBuf, String>) -> Result<Crate, String> {
        let root = ["lib.rs", "main.rs"]
            .iter()
            .map(PathBuf::from)
            .find(|p| files.contains_key(p))
            .ok_or("no lib.rs or main.rs")?;
        let mut krate = Crate::default();
        krate.load_file(files, &root, Vec::new(), PathBuf::new())?;
        Ok(krate)
    }

    /// The module `path` whose source is the file `file`; its `mod x;` children are under `dir`.
    fn load_file(
        &mut self,
        files: &BTreeMap<PathBuf, String>,
        file: &Path,
        path: ModPath,
        dir: PathBuf,
    ) -> Result<(), String> {
        let text = &files[file];
        let parsed = syn::parse_file(text).map_err(|e| format!("{}: {e}", file.display()))?;
        let lines: Vec<&str> = text.lines().collect();
        let source = Source { file, lines: &lines };
        self.load_items(files, &source, &parsed.items, path, dir)
    }

    fn load_items(
        &mut self,
        files: &BTreeMap<PathBuf, String>,
        source: &Source,
        items: &[syn::Item],
        path: ModPath,
        dir: PathBuf,
    ) -> Result<(), String> {
        self.modules.entry(path.clone()).or_default();
        let mut children = Vec::new();
        for item in items {
            if let syn::Item::Mod(m) = item {
                let name = m.ident.to_string();
                self.module(&path).children.insert(name.clone());
                children.push((m, name));
                continue;
            }
            if let Some(name) = item_name(item) {
                self.module(&path).items.insert(name);
            }
            let mut found = Found::default();
            Collector { source, found: &mut found }.visit_item(item);
            self.record(&path, found);
        }
        for (m, name) in children {
            let child = [path.as_slice(), std::slice::from_ref(&name)].concat();
            let child_dir = dir.join(&name);
            match &m.content {
                Some((_, inner)) => self.load_items(files, source, inner, child, child_dir)?,
                None => {
                    let file = child_file(files, source.file, &dir, m)?;
                    let child_dir = if m.attrs.iter().any(|a| a.path().is_ident("path")) {
                        file.parent().unwrap_or(Path::new("")).to_path_buf()
                    } else {
                        child_dir
                    };
                    self.load_file(files, &file, child, child_dir)?;
                }
            }
        }
        Ok(())
    }

    fn module(&mut self, path: &[String]) -> &mut Module {
        self.modules.entry(path.to_vec()).or_default()
    }

    fn record(&mut self, path: &[String], found: Found) {
        let module = self.module(path);
        module.imports.extend(found.imports);
        module.globs.extend(found.globs);
        self.references.extend(found.paths.into_iter().map(|(p, evidence)| Reference {
            from: path.to_vec(),
            path: p,
            evidence,
        }));
    }

    /// The level (parent module) and the sibling edge `r` makes, if it names another sibling.
    fn edge(&self, r: &Reference) -> Option<(ModPath, Edge)> {
        let target = self.absolute(&r.from, &r.path, 0)?;
        let to = self.module_prefix(&target);
        let k = r.from.iter().zip(&to).take_while(|(a, b)| a == b).count();
        if k == r.from.len() || k == to.len() {
            return None; // a module naming its own ancestor or descendant
        }
        let edge = Edge { from: r.from[..=k].to_vec(), to: to[..=k].to_vec(), evidence: r.evidence.clone() };
        Some((r.from[..k].to_vec(), edge))
    }

    /// The longest prefix of `path` that is a module.
    fn module_prefix(&self, path: &[String]) -> ModPath {
        let mut cur = Vec::new();
        for seg in path {
            cur.push(seg.clone());
            if !self.modules.contains_key(&cur) {
                cur.pop();
                break;
            }
        }
        cur
    }

    /// `segs` as written in module `m`, from the crate root with re-exports followed; `None`
    /// for paths outside the crate (another crate, `Self::`, a local name).
    fn absolute(&self, m: &[String], segs: &[String], hops: usize) -> Option<Vec<String>> {
        let first = segs.first()?.as_str();
        let (base, rest): (Vec<String>, &[String]) = match first {
            "crate" | "$crate" => (Vec::new(), &segs[1..]),
            "self" => (m.to_vec(), &segs[1..]),
            "super" => {
                let ups = segs.iter().take_while(|s| *s == "super").count();
                (m[..m.len().checked_sub(ups)?].to_vec(), &segs[ups..])
            }
            _ => (self.in_scope(m, first, hops)?, &segs[1..]),
        };
        Some(self.canonical([base.as_slice(), rest].concat(), hops))
    }

    /// What the bare name `name` stands for in module `m`: a child, an import or a glob's item.
    fn in_scope(&self, m: &[String], name: &str, hops: usize) -> Option<Vec<String>> {
        let module = self.modules.get(m)?;
        if module.children.contains(name) || module.items.contains(name) {
            return Some([m, &[name.to_string()]].concat());
        }
        if hops >= MAX_HOPS {
            return None;
        }
        if let Some(raw) = module.imports.get(name) {
            return self.absolute(m, raw, hops + 1);
        }
        module.globs.iter().find_map(|g| {
            let g = self.absolute(m, g, hops + 1)?;
            let there = self.modules.get(&g)?;
            let has = there.children.contains(name) || there.items.contains(name) || there.imports.contains_key(name);
            has.then(|| self.canonical([g.as_slice(), &[name.to_string()]].concat(), hops + 1))
        })
    }

    /// An absolute path with the re-exports along it replaced by what they name.
    fn canonical(&self, path: Vec<String>, hops: usize) -> Vec<String> {
        let mut cur: Vec<String> = Vec::new();
        for (i, seg) in path.iter().enumerate() {
            let Some(module) = self.modules.get(&cur) else { break };
            if module.children.contains(seg) {
                cur.push(seg.clone());
                continue;
            }
            if module.items.contains(seg) || hops >= MAX_HOPS {
                break;
            }
            if let Some(target) = self.in_scope(&cur, seg, hops + 1) {
                return self.canonical([target.as_slice(), &path[i + 1..]].concat(), hops + 1);
            }
            break;
        }
        path
    }
}

/// The file of `mod x;` declared in `file`, whose children live under `dir`.
fn child_file(files: &BTreeMap<PathBuf, String>, file: &Path, dir: &Path, m: &syn::ItemMod) -> Result<PathBuf, String> {
    for attr in &m.attrs {
        if let syn::Meta::NameValue(nv) = &attr.meta
            && nv.path.is_ident("path")
            && let syn::Expr::Lit(syn::ExprLit { lit: syn::Lit::Str(s), .. }) = &nv.value
        {
            let p = file.parent().unwrap_or(Path::new("")).join(s.value());
            return files.contains_key(&p).then_some(p.clone()).ok_or(format!(
                "{}: no {}",
                file.display(),
                p.display()
            ));
        }
    }
    let name = m.ident.to_string();
    let candidates = [dir.join(format!("{name}.rs")), dir.join(&name).join("mod.rs")];
    candidates.iter().find(|p| files.contains_key(*p)).cloned().ok_or_else(|| {
        format!("{}: mod {name}: neither {} nor {}", file.display(), candidates[0].display(), candidates[1].display())
    })
}

/// The name an item defines in its module's namespace, if any.
fn item_name(item: &syn::Item) -> Option<String> {
    let ident = match item {
        syn::Item::Const(i) => &i.ident,
        syn::Item::Enum(i) => &i.ident,
        syn::Item::Fn(i) => &i.sig.ident,
        syn::Item::Macro(i) => i.ident.as_ref()?,
        syn::Item::Static(i) => &i.ident,
        syn::Item::Struct(i) => &i.ident,
        syn::Item::Trait(i) => &i.ident,
        syn::Item::TraitAlias(i) => &i.ident,
        syn::Item::Type(i) => &i.ident,
        syn::Item::Union(i) => &i.ident,
        _ => return None,
    };
    Some(ident.to_string())
}

struct Source<'a> {
    file: &'a Path,
    lines: &'a [&'a str],
}

impl Source<'_> {
    fn evidence(&self, span: Span, text: Option<String>) -> Evidence {
        let line = span.start().line;
        let is_use = text.is_some();
        let text = text.unwrap_or_else(|| self.lines.get(line.wrapping_sub(1)).unwrap_or(&"").trim().to_string());
        Evidence { file: self.file.to_path_buf(), line, text, is_use }
    }
}

/// What one item says about other modules.
#[derive(Default)]
struct Found {
    paths: Vec<(Vec<String>, Evidence)>,
    imports: Vec<(String, Vec<String>)>,
    globs: Vec<Vec<String>>,
}

/// Collects the paths of one item; nested `mod` items in blocks are not entered.
struct Collector<'a, 'b> {
    source: &'b Source<'a>,
    found: &'b mut Found,
}

impl Collector<'_, '_> {
    fn use_tree(&mut self, tree: &syn::UseTree, prefix: &mut Vec<String>) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                self.use_tree(&p.tree, prefix);
                prefix.pop();
            }
            syn::UseTree::Name(n) => self.use_leaf(prefix, &n.ident, &n.ident),
            syn::UseTree::Rename(r) => self.use_leaf(prefix, &r.ident, &r.rename),
            syn::UseTree::Glob(g) => {
                let span = g.star_token.span;
                let text = format!("use {}::*;", prefix.join("::"));
                self.found.globs.push(prefix.clone());
                self.found.paths.push((prefix.clone(), self.source.evidence(span, Some(text))));
            }
            syn::UseTree::Group(g) => g.items.iter().for_each(|t| self.use_tree(t, prefix)),
        }
    }

    /// `use prefix::ident as name;` (`self` naming the prefix itself).
    fn use_leaf(&mut self, prefix: &[String], ident: &syn::Ident, name: &syn::Ident) {
        let full = if ident == "self" { prefix.to_vec() } else { [prefix, &[ident.to_string()]].concat() };
        let Some(last) = full.last() else { return };
        let alias = if name == "self" { last.clone() } else { name.to_string() };
        let text = if alias == *last {
            format!("use {};", full.join("::"))
        } else {
            format!("use {} as {alias};", full.join("::"))
        };
        if alias != "_" {
            self.found.imports.push((alias, full.clone()));
        }
        self.found.paths.push((full, self.source.evidence(ident.span(), Some(text))));
    }

    /// Paths of two or more segments among a macro's tokens (`assert_eq!(crate::a::f(), 1)`).
    fn tokens(&mut self, tokens: TokenStream) {
        let mut run: Vec<(String, Span)> = Vec::new();
        let mut colons = 0;
        for tt in tokens {
            match tt {
                TokenTree::Ident(i) => {
                    if colons != 2 {
                        self.flush(&mut run);
                    }
                    run.push((i.to_string(), i.span()));
                    colons = 0;
                }
                TokenTree::Punct(p) if p.as_char() == ':' && !run.is_empty() && colons < 2 => colons += 1,
                other => {
                    self.flush(&mut run);
                    colons = 0;
                    if let TokenTree::Group(g) = other {
                        self.tokens(g.stream());
                    }
                }
            }
        }
        self.flush(&mut run);
    }

    fn flush(&mut self, run: &mut Vec<(String, Span)>) {
        if run.len() > 1 {
            let path = run.iter().map(|(s, _)| s.clone()).collect();
            self.found.paths.push((path, self.source.evidence(run[0].1, None)));
        }
        run.clear();
    }
}

impl<'ast> Visit<'ast> for Collector<'_, '_> {
    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        if u.leading_colon.is_none() {
            self.use_tree(&u.tree, &mut Vec::new());
        }
    }

    fn visit_item_mod(&mut self, _: &'ast syn::ItemMod) {}

    fn visit_path(&mut self, p: &'ast syn::Path) {
        if p.leading_colon.is_none() && p.segments.len() > 1 {
            let segs = p.segments.iter().map(|s| s.ident.to_string()).collect();
            self.found.paths.push((segs, self.source.evidence(p.segments[0].ident.span(), None)));
        }
        syn::visit::visit_path(self, p);
    }

    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        self.visit_path(&m.path);
        self.tokens(m.tokens.clone());
    }
}

fn crate_src(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(name).join("src")
}

/// The circles of `crates/<name>`, each as a report naming its files from the workspace root.
fn crate_circles(name: &str) -> Vec<String> {
    let src = crate_src(name);
    let found = circles(&read_src(&src)).unwrap_or_else(|e| panic!("crates/{name}/src: {e}"));
    found.iter().map(|c| c.report(&format!("crates/{name}/src"))).collect()
}

#[test]
fn no_module_circles_in_render_synth_and_capture() {
    let mut report = String::new();
    for name in ["render", "synth", "capture"] {
        for c in crate_circles(name) {
            report += &format!("skinkit-{name} {c}");
        }
    }
    assert!(report.is_empty(), "module circles (issue 38: dependencies between siblings point one way):\n{report}");
}

/// The renderer's layers behind its front door, as other crates would name them.
const BEHIND_THE_FRONT_DOOR: [&str; 4] =
    ["skinkit_render::gpu", "skinkit_render::pass", "skinkit_render::load", "Gpu::new("];

#[test]
fn only_the_renderer_builds_the_device_and_wires_the_passes() {
    // Issue 38: the CLI, the viewer, the demo's figures, the accuracy run and the benchmarks of
    // other crates go through `skinkit_render::renderer`; the render crate's own tests and
    // benches may drive its layers directly.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut folders: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.ends_with("render"))
        .collect();
    folders.push(root.join("tests"));
    let mut found = Vec::new();
    for folder in folders {
        let files = read_src(&folder);
        assert!(!files.is_empty() || !folder.join("src").exists(), "{}: no sources read", folder.display());
        // This file names them in its list.
        for (file, text) in files.into_iter().filter(|(f, _)| !f.ends_with("architecture.rs")) {
            for (n, line) in text.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                if let Some(name) = BEHIND_THE_FRONT_DOOR.iter().find(|name| code.contains(**name)) {
                    found.push(format!("{}/{}:{}: {name}", folder.display(), file.display(), n + 1));
                }
            }
        }
    }
    assert!(found.is_empty(), "outside the renderer's front door:\n{}", found.join("\n"));
}

/// No function over 80 lines, no file over 600 without its reason.
mod sizes;

/// The circle finder's own tests.
mod tests;
