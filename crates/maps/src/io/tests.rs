//! Tests of [`super`]: map and photo round trips, atomic writes.

use super::*;

fn sample_map() -> NormalMap {
    let g = Grid::from_fn(7, 5, |x, y| Vec3::new(x as f32 * 0.1 - 0.3, 0.2 - y as f32 * 0.1, 1.0));
    let mut m = NormalMap::from_grid(g);
    m.set(3, 2, Vec3::ZERO);
    m
}

#[test]
fn normal_map_round_trips_png16_png8_exr() {
    let dir = tempfile::tempdir().unwrap();
    let m = sample_map();
    for (name, bits, tol) in [("n.png", 16, 0.01), ("n8.png", 8, 0.5), ("n.exr", 32, 1e-5)] {
        for green in [crate::GreenAxis::Up, crate::GreenAxis::Down] {
            let enc = NormalEncoding { green };
            let path = dir.path().join(name);
            write_normal_map(&path, &m, enc, bits).unwrap();
            let back = read_normal_map(&path, enc, &Limits::default()).unwrap();
            assert_eq!(back.size(), m.size());
            assert!(!back.is_valid(3, 2), "{name}: invalid texel survives");
            let err = back.angular_error(&m, None).unwrap();
            assert_eq!(err.count, 34);
            assert!(err.max < tol, "{name} {green:?}: {err:?}");
        }
    }
}

#[test]
fn green_down_file_differs_from_green_up() {
    let dir = tempfile::tempdir().unwrap();
    let m = sample_map();
    let path = dir.path().join("n.png");
    write_normal_map(&path, &m, NormalEncoding { green: crate::GreenAxis::Down }, 16).unwrap();
    let misread = read_normal_map(&path, NormalEncoding::default(), &Limits::default()).unwrap();
    assert!((misread.get(0, 0).y + m.get(0, 0).y).abs() < 1e-3);
}

#[test]
fn photos_keep_native_depth() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.png");
    write_png(&path, 2, 2, PngLayout::Gray16, &[0, 1000, 40000, 65535]).unwrap();
    let p = read_photo(&path, &Limits::default()).unwrap();
    assert_eq!(p.samples(), &Samples::U16(vec![0, 1000, 40000, 65535]));
    write_png(&path, 1, 2, PngLayout::Rgb8, &[1, 2, 3, 4, 5, 6]).unwrap();
    let p = read_photo(&path, &Limits::default()).unwrap();
    assert_eq!((p.channels(), p.samples()), (Channels::Rgb, &Samples::U8(vec![1, 2, 3, 4, 5, 6])));
}

#[test]
fn tiff_photos_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.tiff");
    let buf: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
        image::ImageBuffer::from_raw(2, 1, vec![7u16, 65000]).unwrap();
    buf.save(&path).unwrap();
    let p = read_photo(&path, &Limits::default()).unwrap();
    assert_eq!(p.samples(), &Samples::U16(vec![7, 65000]));
}

#[test]
fn bad_files_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("text.png");
    std::fs::write(&text, "hello, not a png").unwrap();
    let e = read_photo(&text, &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("text.png"), "{e}");

    let good = dir.path().join("good.png");
    write_png(&good, 64, 64, PngLayout::Gray16, &vec![1234; 64 * 64]).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.png");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_photo(&cut, &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("cut.png"), "{e}");

    let e = read_photo(&good, &Limits { max_pixels: 100 }).unwrap_err().to_string();
    assert!(e.contains("exceeds"), "{e}");
    assert!(read_photo(&dir.path().join("missing.png"), &Limits::default()).is_err());
}

#[test]
fn every_part_of_a_multi_part_exr_is_checked_against_the_limit() {
    use exr::prelude::{Encoding, Image, ImageAttributes, IntegerBounds, Layer, LayerAttributes};
    use exr::prelude::{SpecificChannels, Vec2, WritableImage};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("parts.exr");
    let pixel = |_: Vec2<usize>| (0.0f32, 0.0f32, 1.0f32);
    let part = |name: &str, side: usize| {
        let channels = SpecificChannels::rgb(pixel);
        Layer::new((side, side), LayerAttributes::named(name), Encoding::UNCOMPRESSED, channels)
    };
    let bounds = IntegerBounds::from_dimensions((16, 16));
    let image = Image::from_layers(ImageAttributes::new(bounds), vec![part("small", 8), part("large", 16)]);
    image.write().to_file(&path).unwrap();
    // The first part (64 pixels) fits 100; the second (256) does not, and the file is refused.
    let e = read_photo(&path, &Limits { max_pixels: 100 }).unwrap_err().to_string();
    assert!(e.contains("parts.exr") && e.contains("16x16"), "{e}");
    let e = crate::limits::image_header(&path, 100).unwrap_err().to_string();
    assert!(e.contains("16x16"), "{e}");
    let header = crate::limits::image_header(&path, 1000).unwrap();
    assert_eq!((header.width, header.height), (8, 8), "the part the reader decodes");
    let photo = read_photo(&path, &Limits { max_pixels: 1000 }).unwrap();
    assert_eq!((photo.width(), photo.height()), (8, 8));
}

#[test]
fn nan_in_exr_becomes_invalid() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.exr");
    write_exr_rgb(&path, 2, 1, |x, _| if x == 0 { [f32::NAN, 0.0, 1.0] } else { [0.0, 0.0, 1.0] }).unwrap();
    let m = read_normal_map(&path, NormalEncoding::default(), &Limits::default()).unwrap();
    assert!(!m.is_valid(0, 0));
    assert_eq!(m.get(1, 0), Vec3::Z);
}

#[test]
fn failed_write_leaves_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keep.txt");
    std::fs::write(&path, "old").unwrap();
    let r = write_atomic(&path, |_| Err(Error::InvalidParameter("boom".into())));
    assert!(r.is_err());
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "temporary file left behind");
}
