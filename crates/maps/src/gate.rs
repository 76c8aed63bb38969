//! The output gate: output paths checked before any work (issue 15, D5 and D14). An output that
//! is one of the command's inputs (or a folder of inputs it would write among) is refused, and so
//! is a folder where a file is written or a file where a folder is: [`Refused`], which the CLI
//! exits with as a usage error (2). Every command that writes passes its outputs through here.
//!
//! Paths are compared canonicalized (symbolic links, `..` and relative forms resolved); an output
//! that does not exist yet is resolved through its deepest existing ancestor.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// An output the gate refuses, with the message naming the flag, the path and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused(pub String);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Refused {}

/// Result alias of the gate.
pub type Result<T = (), E = Refused> = std::result::Result<T, E>;

fn usage(message: String) -> Refused {
    Refused(message)
}

/// `path` made absolute with links resolved as far as it exists.
pub fn resolve(path: &Path) -> PathBuf {
    let absolute = std::env::current_dir().map(|cwd| cwd.join(path)).unwrap_or_else(|_| path.to_owned());
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(canonical) = existing.canonicalize() {
            return rest.iter().rev().fold(canonical, |p, name| p.join(name));
        }
        match (existing.parent(), existing.components().next_back()) {
            (Some(parent), Some(Component::Normal(name))) => {
                rest.push(name.to_owned());
                existing = parent;
            }
            _ => return absolute,
        }
    }
}

/// Refuses an existing folder as the output file `path` of `flag`.
pub fn out_file(flag: &str, path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(usage(format!("{flag} {}: is a folder, but a file is written there", path.display())));
    }
    Ok(())
}

/// Refuses an existing file (not a folder) as the output folder `path` of `flag`.
pub fn out_folder(flag: &str, path: &Path) -> Result<()> {
    if path.exists() && !path.is_dir() {
        return Err(usage(format!("{flag} {}: is a file, but a folder of outputs is written there", path.display())));
    }
    Ok(())
}

/// Refuses an output (`flag`, path) equal to an input (what it is, path). Inputs name what they
/// are: `the exemplar`, `the scene's normal map`.
///
/// Each path is resolved once and looked up in a map, so a render of thousands of frames is
/// checked in linear time (issue 42, D11: pairwise resolving took minutes at 3600 frames).
pub fn not_an_input(outputs: &[(&str, &Path)], inputs: &[(String, PathBuf)]) -> Result<()> {
    let mut by_path: HashMap<PathBuf, (&str, &Path)> = HashMap::with_capacity(inputs.len());
    for (what, input) in inputs {
        by_path.entry(resolve(input)).or_insert((what.as_str(), input.as_path()));
    }
    let resolved: Vec<PathBuf> = outputs.iter().map(|(_, out)| resolve(out)).collect();
    for ((flag, out), path) in outputs.iter().zip(&resolved) {
        if let Some((what, input)) = by_path.get(path) {
            // The input's own spelling only where it differs (a link, a relative path): the
            // file is named once.
            let spelled = if input == out { String::new() } else { format!(" {}", input.display()) };
            return Err(usage(format!(
                "{flag} {} is {what}{spelled}: writing it would destroy the input; choose another output path",
                out.display()
            )));
        }
    }
    distinct_resolved(outputs, &resolved)
}

/// The checks of output files: none is an existing folder ([`out_file`]), an input
/// ([`not_an_input`]) or another output.
pub fn output_files(outputs: &[(&str, &Path)], inputs: &[(String, PathBuf)]) -> Result<()> {
    for (flag, path) in outputs {
        out_file(flag, path)?;
    }
    not_an_input(outputs, inputs)
}

/// The outputs whose flag was given.
pub fn given<'a>(outputs: &[(&'a str, Option<&'a PathBuf>)]) -> Vec<(&'a str, &'a Path)> {
    outputs.iter().filter_map(|(flag, path)| path.map(|p| (*flag, p.as_path()))).collect()
}

/// Refuses two outputs at one path, each output's path already resolved (`resolved[i]` is
/// `outputs[i]`'s).
fn distinct_resolved(outputs: &[(&str, &Path)], resolved: &[PathBuf]) -> Result<()> {
    let mut seen: HashMap<&Path, &str> = HashMap::with_capacity(outputs.len());
    for ((flag, out), path) in outputs.iter().zip(resolved) {
        if let Some(other) = seen.insert(path, flag) {
            return Err(usage(format!("{other} and {flag} are both {}: give each output its own path", out.display())));
        }
    }
    Ok(())
}

/// Refuses an output folder `out` (of `flag`) that is the input folder `dir` (what it is) or lies
/// inside it: the outputs would land among the inputs and be taken for inputs by the next run.
pub fn not_in_input_folder(flag: &str, out: &Path, what: &str, dir: &Path) -> Result<()> {
    if resolve(out).starts_with(resolve(dir)) {
        let (place, spelled) =
            if out == dir { ("", String::new()) } else { ("inside ", format!(" {}", dir.display())) };
        return Err(usage(format!(
            "{flag} {} is {place}{what}{spelled}: outputs would be mixed with the inputs; choose a folder outside it",
            out.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d5_paths_are_compared_canonicalized() {
        let tmp = tempfile::tempdir().unwrap();
        let input = tmp.path().join("in.png");
        std::fs::write(&input, "x").unwrap();
        std::fs::create_dir(tmp.path().join("sub")).unwrap();
        let roundabout = tmp.path().join("sub/../in.png");
        let inputs = [("the exemplar".to_owned(), input.clone())];
        let e = not_an_input(&[("--out", &roundabout)], &inputs).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("--out") && text.contains("the exemplar") && text.contains("in.png"), "{text}");
        #[cfg(unix)]
        {
            let link = tmp.path().join("link");
            std::os::unix::fs::symlink(tmp.path().join("sub"), &link).unwrap();
            assert_eq!(resolve(&link.join("new/x.png")), resolve(&tmp.path().join("sub/new/x.png")));
        }
        assert!(not_an_input(&[("--out", &tmp.path().join("other.png"))], &inputs).is_ok());
        let e =
            not_an_input(&[("--out", &tmp.path().join("a.png")), ("--report", &tmp.path().join("sub/../a.png"))], &[]);
        assert!(e.unwrap_err().to_string().contains("--out and --report"));
    }

    /// D11: an orbit at the frame limit (3600 frames) checked its outputs pair by pair, 7.5
    /// minutes before the first frame; they are now one set, each path resolved once, and the one
    /// repeated among them is still named with the first that had it.
    #[test]
    fn probe2_d11_an_orbits_frames_are_checked_as_one_set() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::create_dir(tmp.path().join("sub")).unwrap();
        let input = tmp.path().join("in.png");
        let inputs = [("the normal map".to_owned(), input)];
        let frames: Vec<PathBuf> = (0..3600).map(|f| tmp.path().join(format!("f{f:04}.png"))).collect();
        let mut outputs: Vec<(&str, &Path)> = frames.iter().map(|p| ("--out", p.as_path())).collect();
        assert!(not_an_input(&outputs, &inputs).is_ok());
        let report = tmp.path().join("sub/../f3599.png");
        outputs.push(("--report", &report));
        let text = not_an_input(&outputs, &inputs).unwrap_err().to_string();
        assert!(text.contains("--out and --report") && text.contains("f3599.png"), "{text}");
    }

    #[test]
    fn d5_an_output_folder_inside_the_input_folder_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let e = not_in_input_folder("--out", &tmp.path().join("a/b"), "the sessions folder", tmp.path());
        assert!(e.unwrap_err().to_string().contains("inside the sessions folder"));
        assert!(not_in_input_folder("--out", tmp.path(), "x", &tmp.path().join("a")).is_ok());
    }

    #[test]
    fn d14_wrong_kinds_of_output_are_usage_errors() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("f.txt");
        std::fs::write(&file, "x").unwrap();
        assert!(out_file("--out", tmp.path()).unwrap_err().0.contains("is a folder"));
        assert!(out_folder("--out", &file).unwrap_err().0.contains("is a file"));
        assert!(out_file("--out", &file).is_ok() && out_folder("--out", tmp.path()).is_ok());
    }
}
