//! Opening a page in headless Chromium (`tools/page-check/check-page.mjs`) from a test.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `node` and the page checker's packages (`tools/page-check`, installed with npm when missing),
/// and the system's Chromium: the checker's script, or why it cannot run here.
pub fn page_checker() -> Result<PathBuf, String> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/page-check");
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !Path::new(&chromium).is_file() {
        return Err(format!("no Chromium at {chromium} (Debian: apt-get install chromium; scripts/test installs it)"));
    }
    let runs = |program: &str, args: &[&str]| {
        Command::new(program).args(args).current_dir(&tools).output().is_ok_and(|o| o.status.success())
    };
    if !runs("node", &["--version"]) {
        return Err("no node (Debian: apt-get install nodejs npm)".into());
    }
    if !tools.join("node_modules/playwright-core").is_dir()
        && !runs("npm", &["ci", "--no-audit", "--no-fund", "--silent"])
    {
        return Err(format!("npm ci failed in {}", tools.display()));
    }
    Ok(tools.join("check-page.mjs"))
}

/// What the checker saw of `page` (no screenshot): images, rows, errors.
pub fn open(checker: &Path, page: &Path) -> serde_json::Value {
    let o = Command::new("node").arg(checker).arg(page).arg("-").output().expect("node runs");
    assert!(o.status.success(), "check-page.mjs failed: {}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}
