//! The stitch side of the resource policy (issue 15): a resampled exemplar's size and its
//! synthesis estimate are checked before it is resampled (D1), the coverage mask from its header
//! before it is decoded, and a map at the size limit from its numbers before anything of its size
//! is allocated (D6). Heap use is measured by a counting allocator: each measured call holds a
//! lock, so no other test of this binary allocates meanwhile.

use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use skinkit_maps::NormalMap;
use skinkit_stitch::compose::{MAP_BYTES_PER_TEXEL, check_memory};
use skinkit_stitch::curve::CurveParams;
use skinkit_stitch::layout::Layout;
use skinkit_stitch::{ComposeOptions, compose};
use skinkit_synth::SynthConfig;

/// The system allocator, counting the bytes held and their peak.
struct Counting;

static HELD: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static MEASURING: Mutex<()> = Mutex::new(());

fn grew(bytes: usize) {
    let now = HELD.fetch_add(bytes, Ordering::SeqCst) + bytes;
    PEAK.fetch_max(now, Ordering::SeqCst);
}

// SAFETY: every call is forwarded to `System` unchanged; only counters are updated beside it.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: AllocLayout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: AllocLayout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: AllocLayout) {
        unsafe { System.dealloc(ptr, layout) };
        HELD.fetch_sub(layout.size(), Ordering::SeqCst);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: AllocLayout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            HELD.fetch_sub(layout.size(), Ordering::SeqCst);
            grew(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Holds every other test of this binary off while a test allocates: each test takes it for
/// its whole body, so a measurement sees only its own allocations.
fn alone() -> std::sync::MutexGuard<'static, ()> {
    MEASURING.lock().unwrap_or_else(|e| e.into_inner())
}

/// `f`'s result and the most heap bytes it held at once above what was held before it (call it
/// while holding [`alone`]).
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = HELD.load(Ordering::SeqCst);
    PEAK.store(base, Ordering::SeqCst);
    let result = f();
    (result, PEAK.load(Ordering::SeqCst).saturating_sub(base))
}

const MIB: usize = 1 << 20;

/// Two regions on a `w x h` map at 0.05 mm per texel; region `b`'s exemplar is `scale` mm per
/// texel; `extra` goes on top of the file.
fn layout(dir: &Path, w: usize, h: usize, scale: f64, extra: &str) -> Layout {
    let text = format!(
        r#"{extra}
size = [{w}, {h}]
mm_per_texel = 0.05
[[region]]
name = "a"
exemplar = "a.png"
exemplar_mm_per_texel = 0.05
points = [[0.25, 0.5]]
[[region]]
name = "b"
exemplar = "b.png"
exemplar_mm_per_texel = {scale}
points = [[0.75, 0.5]]
"#
    );
    Layout::parse(&text, &dir.join("layout.toml")).unwrap()
}

fn options() -> ComposeOptions {
    ComposeOptions {
        curve: CurveParams::straight(),
        synth: SynthConfig { memory_limit: 8 << 30, ..SynthConfig::default() },
        ..ComposeOptions::default()
    }
}

fn exemplars() -> Vec<NormalMap> {
    vec![NormalMap::flat(64, 64), NormalMap::flat(256, 256)]
}

#[test]
fn d1_huge_exemplar_scale_is_refused_before_allocating() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 512, 256, 1e9, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &|_| {}));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("layout.toml: region `b`: exemplar_mm_per_texel"), "{e}");
    assert!(e.contains("over the limit of 268435456 texels"), "{e}");
    assert!(peak < 16 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d1_an_exemplar_whose_synthesis_cannot_fit_is_refused_before_resampling() {
    let _alone = alone();
    // 3 mm against 0.05: the 256x256 exemplar would become 15360x15360 (2.7 GB of normals, which
    // the probe saw allocated) before the synthesis estimate refused it.
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 512, 256, 3.0, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &|_| {}));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("region `b`") && e.contains("15360x15360") && e.contains("needs an estimated"), "{e}");
    assert!(peak < 64 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d6_a_coverage_bomb_is_refused_from_its_header() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    // A real 32768x32768 8-bit PNG of zeros would be about 1 MB; its header is all it takes.
    header_only_png(&dir.path().join("bomb.png"), 32768, 32768);
    let l = layout(dir.path(), 512, 256, 0.05, "coverage = \"bomb.png\"");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &|_| {}));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("coverage") && e.contains("bomb.png is 32768x32768 but the map is 512x256"), "{e}");
    assert!(peak < 4 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d6_a_map_at_the_size_limit_is_refused_before_anything_is_allocated() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 32768, 32768, 0.05, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &|_| {}));
    let e = result.unwrap_err().to_string();
    // 2^30 texels at 28 bytes: 28 GiB.
    assert!(e.contains("layout.toml: size: a 32768x32768 face map needs an estimated 28672 MiB"), "{e}");
    assert!(e.contains("memory limit of 8192 MiB"), "{e}");
    assert!(peak < MIB, "{} bytes held before refusing", peak);
    assert!(check_memory(&l, &options()).is_err(), "callers can check before reading exemplars");
}

#[test]
fn d6_the_map_floor_is_below_what_a_compose_holds() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 128, 64, 0.05, "");
    let (composed, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &|_| {}).unwrap());
    let floor = 128 * 64 * MAP_BYTES_PER_TEXEL as usize;
    eprintln!("128x64 map: floor {floor} bytes, heap peak {peak} bytes ({:.1}x)", peak as f64 / floor as f64);
    assert!(peak >= floor, "the floor {floor} is above the measured peak {peak}");
    drop(composed);
}

/// A PNG of `w x h` 8-bit grey pixels whose header is all there is (no pixel data).
fn header_only_png(path: &Path, w: u32, h: u32) {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend_from_slice(&13u32.to_be_bytes());
    bytes.extend_from_slice(&ihdr);
    bytes.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    // A one-byte zlib stream (a stored block) as the only image data, then the end: the file is
    // well formed up to the pixels and far too short for the size it claims.
    let idat = [b'I', b'D', b'A', b'T', 0x78, 0x01, 0x01, 0x01, 0x00, 0xFE, 0xFF, 0x00, 0x00, 0x01, 0x00, 0x01];
    bytes.extend_from_slice(&12u32.to_be_bytes());
    bytes.extend_from_slice(&idat);
    bytes.extend_from_slice(&crc32(&idat).to_be_bytes());
    bytes.extend_from_slice(&[0, 0, 0, 0, b'I', b'E', b'N', b'D', 0xAE, 0x42, 0x60, 0x82]);
    std::fs::write(path, bytes).unwrap();
}

fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}
