use super::*;

/// Issue 42, D9: a sparse 3 GiB rig is refused from its length, before a byte is read.
#[test]
fn d9_a_file_over_its_kinds_limit_is_refused_unread() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig.toml");
    File::create(&path).unwrap().set_len(3 << 30).unwrap();
    let e = read_to_string(&path, Kind::Toml).unwrap_err();
    assert!(matches!(e, InputError::TooLarge { len, .. } if len == 3 << 30), "{e}");
    let text = e.to_string();
    assert!(text.contains("rig.toml") && text.contains("a TOML file") && text.contains("16 MiB"), "{text}");
}

/// Issue 42, D9: `/dev/zero` as a rig or a mesh is a device, refused without reading it.
#[cfg(unix)]
#[test]
fn d9_a_device_is_refused_as_any_kind() {
    for kind in [Kind::Toml, Kind::Mesh, Kind::Image] {
        let e = read(Path::new("/dev/zero"), kind).unwrap_err().to_string();
        assert!(e.starts_with("/dev/zero: a device, not a regular file"), "{e}");
        assert!(e.contains(kind.name()), "{e}");
    }
}

/// Issue 42, D10: a FIFO nobody writes to is refused at once, not waited on.
#[cfg(unix)]
#[test]
fn d10_a_fifo_is_refused_without_blocking() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("03.png");
    let name = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o644) }, 0);
    let e = open(&path, Kind::Image).unwrap_err().to_string();
    assert!(e.contains("03.png: a FIFO (named pipe), not a regular file (an image is read"), "{e}");
}

#[test]
fn a_folder_is_refused_and_a_small_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let e = open(dir.path(), Kind::Mesh).unwrap_err().to_string();
    assert!(e.contains("a folder, not a regular file (a mesh is read only"), "{e}");
    let path = dir.path().join("a.toml");
    std::fs::write(&path, "x = 1\n").unwrap();
    assert_eq!(read_to_string(&path, Kind::Toml).unwrap(), "x = 1\n");
    let missing = read(&dir.path().join("none.toml"), Kind::Toml).unwrap_err();
    assert!(matches!(missing, InputError::Io { .. }) && missing.path().ends_with("none.toml"));
}

#[test]
fn text_that_is_not_utf8_is_refused_in_std_words() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.toml");
    std::fs::write(&path, b"\xff\xfe").unwrap();
    let e = crate::error::one_line(&read_to_string(&path, Kind::Toml).unwrap_err());
    assert!(e.ends_with("a.toml: stream did not contain valid UTF-8"), "{e}");
}
