use std::sync::atomic::{AtomicUsize, Ordering};

use skinkit_testkit::header_only_png;

use super::*;
use crate::io::{PngLayout, write_png};

#[test]
fn meminfo_total_is_read_in_bytes() {
    let text = "MemTotal:       24576000 kB\nMemFree:         1000 kB\n";
    assert_eq!(parse_meminfo(text), Some(24_576_000 * 1024));
    assert_eq!(parse_meminfo("MemFree: 3 kB\n"), None);
    assert_eq!(parse_meminfo("MemTotal: 3 MB\n"), None, "an unknown unit is not guessed");
}

#[test]
fn memory_sizes_parse_with_binary_units() {
    assert_eq!(parse_bytes("800M"), Ok(800 << 20));
    assert_eq!(parse_bytes("12G"), Ok(12 << 30));
    assert_eq!(parse_bytes("12GiB"), Ok(12 << 30));
    assert_eq!(parse_bytes("1.5g"), Ok(3 << 29));
    assert_eq!(parse_bytes("1T"), Ok(1 << 40));
    assert_eq!(parse_bytes("2097152"), Ok(2 << 20));
    for bad in ["", "G", "12X", "-1G", "0", "1K", "nan", "1e400", "12 G G"] {
        let e = parse_bytes(bad).unwrap_err();
        assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
    }
    assert!(parse_bytes("0%").is_err() && parse_bytes("101%").is_err());
    if let Some(total) = machine_memory() {
        let half = parse_bytes("50%").unwrap();
        assert!(half.abs_diff(total / 2) <= 1, "{half} vs {total}");
        assert_eq!(default_memory_limit(), (total as f64 * DEFAULT_MEMORY_FRACTION) as u64);
    }
}

#[test]
fn thread_limit_scales_with_the_cores() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert_eq!(max_threads(), (cores * THREADS_PER_CORE).max(MIN_MAX_THREADS));
}

#[test]
fn pixel_products_never_overflow() {
    let p = Path::new("x.png");
    assert_eq!(check_pixels(p, 3, 5, 15).unwrap(), 15);
    assert!(check_pixels(p, 4, 4, 15).unwrap_err().to_string().contains("4x4 exceeds the limit of 15"));
    let e = check_pixels(p, u64::MAX, 3, u64::MAX).unwrap_err().to_string();
    assert!(e.contains("x.png") && e.contains("exceeds"), "{e}");
    assert!(check_pixels(p, 0, 3, 100).unwrap_err().to_string().contains("zero size"));
}

#[test]
fn memory_refusals_name_the_subject_and_both_sizes() {
    assert!(check_memory("a.toml", "region `b`", 100, 100).is_ok());
    let e = check_memory("a.toml", "region `b`", (3 << 30) + 1, 2 << 30).unwrap_err().to_string();
    assert!(e.starts_with("a.toml: region `b` needs an estimated 3073 MiB"), "{e}");
    assert!(e.contains("memory limit of 2048 MiB"), "{e}");
}

#[test]
fn d6_headers_are_read_without_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = dir.path().join("bomb.png");
    header_only_png(&bomb, 32768, 32768);
    // The header is all there is: no pixels to decode.
    let h = image_header(&bomb, MAX_MAP_TEXELS).unwrap();
    assert_eq!((h.width, h.height, h.channels, h.alpha, h.sample_bytes), (32768, 32768, 1, false, 1));
    assert_eq!(h.decoded_bytes(), 1 << 30);
    let e = image_header(&bomb, MAX_IMAGE_PIXELS).unwrap_err().to_string();
    assert!(e.contains("bomb.png") && e.contains("32768x32768 exceeds the limit of 268435456"), "{e}");

    let rgb = dir.path().join("rgb.png");
    write_png(&rgb, 5, 3, PngLayout::Rgb16, &[7; 45]).unwrap();
    let h = image_header(&rgb, 15).unwrap();
    assert_eq!((h.width, h.height, h.channels, h.alpha, h.sample_bytes), (5, 3, 3, false, 2));
    assert_eq!(h.decoded_bytes(), 5 * 3 * 3 * 2);
    let grey = ImageHeader { width: 4, height: 2, channels: 2, alpha: true, sample_bytes: 1 };
    assert_eq!(grey.decoded_bytes(), 8 * (1 + 2), "the grey samples kept plus the grey+alpha buffer");

    let exr = dir.path().join("n.exr");
    crate::io::write_exr_rgb(&exr, 6, 4, |_, _| [0.0, 0.0, 1.0]).unwrap();
    let h = image_header(&exr, MAX_IMAGE_PIXELS).unwrap();
    assert_eq!((h.width, h.height, h.decoded_bytes()), (6, 4, 6 * 4 * 12));
    let text = dir.path().join("t.png");
    std::fs::write(&text, "not an image").unwrap();
    assert!(image_header(&text, MAX_IMAGE_PIXELS).unwrap_err().to_string().contains("t.png"));
}

#[test]
fn d9_gate_never_admits_more_than_its_budget() {
    let gate = MemoryGate::new(10);
    assert!(gate.fits(10) && !gate.fits(11));
    let running = AtomicUsize::new(0);
    let in_use = AtomicUsize::new(0);
    let sizes = [6u64, 5, 4, 7, 3, 10, 1, 2, 9, 5, 5, 5];
    std::thread::scope(|s| {
        for &bytes in &sizes {
            let (gate, running, in_use) = (&gate, &running, &in_use);
            s.spawn(move || {
                let _admitted = gate.acquire(bytes);
                running.fetch_add(1, Ordering::SeqCst);
                let now = in_use.fetch_add(bytes as usize, Ordering::SeqCst) + bytes as usize;
                assert!(now <= 10, "{now} bytes admitted at once");
                std::thread::sleep(std::time::Duration::from_millis(5));
                in_use.fetch_sub(bytes as usize, Ordering::SeqCst);
            });
        }
    });
    assert_eq!(running.load(Ordering::SeqCst), sizes.len(), "every job ran");
    let (peak_jobs, peak_bytes) = gate.peaks();
    assert!(peak_bytes <= 10 && peak_jobs >= 1, "{peak_jobs} {peak_bytes}");
    // Released: the whole budget is free again.
    drop(gate.acquire(10));
}

#[test]
fn d9_queued_jobs_keep_their_order_and_fit_the_gate() {
    let gate = MemoryGate::new(8);
    let in_use = AtomicUsize::new(0);
    let peak = AtomicUsize::new(0);
    let sizes: Vec<u64> = (0..40).map(|i| 1 + (i * 7 % 8)).collect();
    let results = run_queued(&sizes, 6, |&bytes| {
        let _admitted = gate.acquire(bytes);
        let now = in_use.fetch_add(bytes as usize, Ordering::SeqCst) + bytes as usize;
        peak.fetch_max(now, Ordering::SeqCst);
        std::thread::sleep(std::time::Duration::from_millis(2));
        in_use.fetch_sub(bytes as usize, Ordering::SeqCst);
        bytes * 10
    });
    assert_eq!(results, sizes.iter().map(|b| b * 10).collect::<Vec<_>>());
    assert!(peak.load(Ordering::SeqCst) <= 8, "{}", peak.load(Ordering::SeqCst));
    assert!(gate.peaks().0 >= 2, "small jobs ran side by side: {:?}", gate.peaks());
    assert!(run_queued(&[] as &[u8], 4, |_| 0).is_empty());
}
