//! What machine a report was measured on: times mean little without it.

use serde::Serialize;

/// The machine a command ran on, as far as the operating system says (fields it does not say are
/// `None`; nothing here fails).
#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    /// CPU model name (Linux: `/proc/cpuinfo`).
    pub cpu: Option<String>,
    /// Threads this process may use.
    pub threads: usize,
    /// Physical memory, GiB (Linux: `/proc/meminfo`).
    pub memory_gib: Option<f64>,
    /// Operating system (Linux: `PRETTY_NAME` of `/etc/os-release`; else the target's OS).
    pub os: String,
    /// The skinkit version that measured.
    pub skinkit: &'static str,
}

impl Machine {
    /// This machine.
    pub fn this() -> Self {
        let read = |path: &str| std::fs::read_to_string(path).ok();
        let field = |text: &str, key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(key)?.trim_start().strip_prefix([':', '='])?.trim().to_owned().into())
                .filter(|v: &String| !v.is_empty())
        };
        let cpu = read("/proc/cpuinfo").and_then(|t| field(&t, "model name"));
        let memory_gib = read("/proc/meminfo")
            .and_then(|t| field(&t, "MemTotal"))
            .and_then(|v| v.trim_end_matches("kB").trim().parse::<f64>().ok())
            .map(|kib| kib / (1u64 << 20) as f64);
        let os = read("/etc/os-release")
            .and_then(|t| field(&t, "PRETTY_NAME"))
            .map(|v| v.trim_matches('"').to_owned())
            .unwrap_or_else(|| std::env::consts::OS.to_owned());
        Machine { cpu, threads: rayon::current_num_threads(), memory_gib, os, skinkit: env!("CARGO_PKG_VERSION") }
    }

    /// One line: "AMD EPYC, 2 threads, 23.4 GiB, Debian GNU/Linux 12 (bookworm)".
    pub fn summary(&self) -> String {
        let mut parts = vec![self.cpu.clone().unwrap_or_else(|| "unknown CPU".into())];
        parts.push(format!("{} threads", self.threads));
        if let Some(m) = self.memory_gib {
            parts.push(format!("{m:.1} GiB"));
        }
        parts.push(self.os.clone());
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_machine_has_threads_and_a_summary() {
        let m = Machine::this();
        assert!(m.threads >= 1);
        assert!(m.summary().contains("threads"), "{}", m.summary());
        assert!(m.memory_gib.is_none_or(|g| g > 0.0 && g.is_finite()));
    }
}
