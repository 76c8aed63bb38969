//! Checks of mesh files against their own text and byte ranges, made before the parsers turn
//! them into a mesh (issue 15, D12).
//!
//! `tobj` re-indexes an OBJ file into one index per vertex and forgets where each value came
//! from, so a NaN on the 50th `v` line would surface as "vertex 42", and an out-of-range face
//! index as a bare "face vertex index out of bounds". Reading the text once beforehand names the
//! source line instead. The `gltf` reader likewise answers "no positions" when an accessor
//! overruns its buffer view, and reads a view past its buffer's end as empty; checking the byte
//! ranges first names the accessor or view at fault.

use super::MeshError;

/// The kinds of OBJ vertex data a face may refer to, in the order of a face token `v/vt/vn`.
const KINDS: [&str; 3] = ["v", "vt", "vn"];

/// Checks every `v`, `vt` and `vn` line for non-finite numbers and every face index for range,
/// naming the source line. Lines the parser would refuse for other reasons are left to it.
///
/// # Errors
/// [`MeshError::ObjLine`] for the first offending line.
pub(crate) fn check_obj(text: &str, file: &str) -> Result<(), MeshError> {
    let total = count_vertex_lines(text);
    let mut seen = [0usize; 3];
    for (number, line) in text.lines().enumerate() {
        let at = |reason: String| MeshError::ObjLine { file: file.to_owned(), line: number + 1, reason };
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        if let Some(kind) = KINDS.iter().position(|k| *k == key) {
            seen[kind] += 1;
            check_numbers(key, words).map_err(at)?;
        } else if key == "f" {
            for token in words {
                check_face_token(token, &seen, &total).map_err(at)?;
            }
        }
    }
    Ok(())
}

/// How many `v`, `vt` and `vn` lines the whole file has.
fn count_vertex_lines(text: &str) -> [usize; 3] {
    let mut total = [0usize; 3];
    for line in text.lines() {
        if let Some(kind) = line.split_whitespace().next().and_then(|key| KINDS.iter().position(|k| *k == key)) {
            total[kind] += 1;
        }
    }
    total
}

/// A vertex line's numbers must be finite where they parse (unparsable ones are the parser's).
fn check_numbers<'a>(key: &str, words: impl Iterator<Item = &'a str>) -> Result<(), String> {
    let values: Vec<f32> = words.filter_map(|w| w.parse::<f32>().ok()).collect();
    if values.iter().any(|v| !v.is_finite()) {
        let shown: Vec<String> = values.iter().map(f32::to_string).collect();
        return Err(format!("`{key}` has a non-finite value ({})", shown.join(", ")));
    }
    Ok(())
}

/// One face token `v`, `v/vt`, `v//vn` or `v/vt/vn`: each index in range. Positive indices count
/// from the file's first line of their kind (up to its last), negative ones back from the
/// latest line of their kind before the face.
fn check_face_token(token: &str, seen: &[usize; 3], total: &[usize; 3]) -> Result<(), String> {
    for (kind, part) in token.split('/').enumerate().take(3) {
        if part.is_empty() {
            continue;
        }
        let Ok(index) = part.parse::<i64>() else {
            return Err(format!("face vertex `{token}`: `{part}` is not an index"));
        };
        let key = KINDS[kind];
        let ok = match index {
            0 => false,
            i if i > 0 => i as u64 <= total[kind] as u64,
            i => i.unsigned_abs() <= seen[kind] as u64,
        };
        if !ok {
            let reason = match index {
                0 => "OBJ indices start at 1".to_owned(),
                i if i > 0 => format!("the file has {} `{key}` lines", total[kind]),
                _ => format!("only {} `{key}` lines come before it", seen[kind]),
            };
            return Err(format!("face vertex `{token}`: `{key}` index {index} is out of range ({reason})"));
        }
    }
    Ok(())
}

/// Checks that every accessor of `primitive` (attributes and indices) lies inside its buffer
/// view, and every such view inside its loaded buffer.
///
/// # Errors
/// A message naming the accessor or view and the byte counts.
pub(crate) fn check_gltf_primitive(
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    name: &str,
) -> Result<(), String> {
    let attributes = primitive.attributes().map(|(semantic, accessor)| (Some(semantic), accessor));
    for (semantic, accessor) in attributes.chain(primitive.indices().map(|a| (None, a))) {
        let what = semantic.as_ref().map_or_else(|| "indices".to_owned(), ToString::to_string);
        check_layout(&accessor, semantic.as_ref())
            .and_then(|()| check_accessor(&accessor, buffers))
            .map_err(|reason| format!("{name}: {what}: {reason}"))?;
    }
    Ok(())
}

/// Checks that an accessor the importer reads has the element layout the glTF specification
/// gives its semantic (indices for `None`): the `gltf` crate's readers assume it, and read a
/// mismatched one past its elements or hit `unreachable!` (found by the `gltf` fuzz target).
/// Semantics the importer does not read are left alone.
fn check_layout(accessor: &gltf::Accessor, semantic: Option<&gltf::Semantic>) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let (dimensions, types): (Dimensions, &[DataType]) = match semantic {
        None => (Dimensions::Scalar, &[DataType::U8, DataType::U16, DataType::U32]),
        Some(Semantic::Positions | Semantic::Normals) => (Dimensions::Vec3, &[DataType::F32]),
        Some(Semantic::Tangents) => (Dimensions::Vec4, &[DataType::F32]),
        Some(Semantic::TexCoords(_)) => (Dimensions::Vec2, &[DataType::F32, DataType::U8, DataType::U16]),
        Some(_) => return Ok(()),
    };
    if accessor.dimensions() != dimensions || !types.contains(&accessor.data_type()) {
        return Err(format!(
            "accessor {} holds {:?} of {:?}, where {:?} of {} is read",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type(),
            dimensions,
            types.iter().map(|t| format!("{t:?}")).collect::<Vec<_>>().join(" or ")
        ));
    }
    Ok(())
}

/// Parses a glTF or GLB file and validates it as the `gltf` crate does, after first checking what
/// the crate reads without a check: a GLB length shorter than its header, and a primitive
/// attribute naming an accessor beyond the file's list (both panicked; found by the `gltf` fuzz
/// target).
///
/// # Errors
/// The crate's parse or validation error, or a message naming the mesh, primitive and attribute.
pub(crate) fn parse_gltf(bytes: &[u8]) -> Result<gltf::Gltf, String> {
    // A GLB header's length below the header's own 12 bytes underflows in the crate's reader (a
    // panic with overflow checks, found by the fuzz target; a wrapped length without them).
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
        if length < 12 {
            return Err(format!("GLB header: total length {length} is shorter than the 12-byte header"));
        }
    }
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let root = document.into_json();
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &primitive.attributes {
                if index.value() >= accessors {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "an invalid attribute".to_owned(),
                    };
                    return Err(format!(
                        "mesh {m} primitive {p}: {name} names accessor {} but the file has {accessors}",
                        index.value()
                    ));
                }
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf { document, blob })
}

/// Checks every external buffer URI before it is resolved: its percent-encoding must decode to
/// UTF-8 (the `gltf` crate unwraps that decoding and would panic). Data URIs and GLB blobs are
/// left to the crate; external files are read by [`load_gltf_buffers`] through the input gate.
///
/// # Errors
/// A message naming the buffer and its URI.
pub(crate) fn check_gltf_buffer_uris(document: &gltf::Document) -> Result<(), String> {
    for buffer in document.buffers() {
        let gltf::buffer::Source::Uri(uri) = buffer.source() else { continue };
        if uri.starts_with("data:") {
            continue;
        }
        let named = |why: &str| format!("buffer {} (uri `{uri}`): {why}", buffer.index());
        percent_decode(uri).ok_or_else(|| named("its percent-encoding is not UTF-8"))?;
    }
    Ok(())
}

/// The data of every buffer of `document`: external files through the input gate
/// ([`skinkit_maps::input`], [`skinkit_maps::input::Kind::GltfBuffer`]), so a FIFO, a device or
/// an oversized file is refused unread; the GLB blob and data URIs through the `gltf` crate.
///
/// # Errors
/// A message naming the buffer: the gate's refusal, a short buffer, or the crate's error.
pub(crate) fn load_gltf_buffers(
    document: &gltf::Document,
    base: &std::path::Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<gltf::buffer::Data>, String> {
    check_gltf_buffer_uris(document)?;
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let named = |why: String| format!("buffer {}: {why}", buffer.index());
        let data = match buffer.source() {
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                let decoded = percent_decode(uri).unwrap_or_default();
                let path =
                    decoded.strip_prefix("file://").or_else(|| decoded.strip_prefix("file:")).unwrap_or(&decoded);
                let mut bytes = skinkit_maps::input::read(&base.join(path), skinkit_maps::input::Kind::GltfBuffer)
                    .map_err(|e| format!("buffer {} (uri `{uri}`): {e}", buffer.index()))?;
                bytes.resize(bytes.len().next_multiple_of(4), 0);
                gltf::buffer::Data(bytes)
            }
            source => {
                gltf::buffer::Data::from_source_and_blob(source, None, &mut blob).map_err(|e| named(e.to_string()))?
            }
        };
        if data.len() < buffer.length() {
            return Err(named(format!("{} bytes, but the file declares {}", data.len(), buffer.length())));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// `%XX` escapes decoded, or `None` when an escape is malformed or the bytes are not UTF-8.
pub(crate) fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn check_accessor(accessor: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    // A view-less accessor is all zeros (or sparse): nothing to overrun.
    let Some(view) = accessor.view() else { return Ok(()) };
    let buffer = view.buffer().index();
    let available = buffers.get(buffer).map_or(0, |d| d.0.len());
    let view_end = view.offset().saturating_add(view.length());
    if view_end > available {
        return Err(format!(
            "bufferView {} (bytes {}..{}) lies past the end of buffer {buffer} ({available} bytes)",
            view.index(),
            view.offset(),
            view_end
        ));
    }
    let count = accessor.count();
    if count == 0 {
        return Ok(());
    }
    let element = accessor.size();
    let stride = view.stride().unwrap_or(element).max(element);
    let needed = (count as u128 - 1) * stride as u128 + element as u128 + accessor.offset() as u128;
    if needed > view.length() as u128 {
        return Err(format!(
            "accessor {} has {count} elements of {element} bytes (from byte {}), {needed} bytes in all, but bufferView {} holds {}",
            accessor.index(),
            accessor.offset(),
            view.index(),
            view.length()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn percent_decoding_refuses_what_is_not_utf8() {
        assert_eq!(super::percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(super::percent_decode("plain.bin").as_deref(), Some("plain.bin"));
        assert_eq!(super::percent_decode("%FF"), None);
        assert_eq!(super::percent_decode("%G0"), None);
        assert_eq!(super::percent_decode("cut%2"), None);
    }

    use super::*;

    fn reason(text: &str) -> String {
        check_obj(text, "t.obj").unwrap_err().to_string()
    }

    #[test]
    fn a_clean_obj_passes() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\nf -3/-3 -2/-2 -1/-1\n";
        check_obj(text, "t.obj").unwrap();
    }

    #[test]
    fn a_non_finite_vertex_names_its_line() {
        let text = "# head\nv 0 0 0\nv nan 0 0\nv 0 inf 0\n";
        assert_eq!(reason(text), "t.obj: line 3: `v` has a non-finite value (NaN, 0, 0)");
        assert!(reason("vt 0 0\nvt 0 -inf\n").starts_with("t.obj: line 2: `vt`"));
    }

    #[test]
    fn out_of_range_face_indices_name_their_line() {
        let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
        assert_eq!(
            reason(&format!("{head}f 1 2 99999\n")),
            "t.obj: line 5: face vertex `99999`: `v` index 99999 is out of range (the file has 3 `v` lines)"
        );
        assert!(reason(&format!("{head}f 1 2 -4\n")).contains("line 5: face vertex `-4`: `v` index -4"));
        assert!(reason(&format!("{head}f 1/1 2/1 3/7\n")).contains("`vt` index 7"));
        assert!(reason(&format!("{head}f 0 1 2\n")).contains("OBJ indices start at 1"));
        assert!(reason(&format!("{head}f 1 2 x\n")).contains("`x` is not an index"));
    }

    #[test]
    fn a_negative_index_counts_back_from_the_face() {
        // Two `v` lines before the face, a third after it: -3 reaches before the first.
        let text = "v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n";
        assert!(reason(text).contains("only 2 `v` lines come before it"));
    }
}
