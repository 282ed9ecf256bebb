//! Gzip-compressed input: scenes and meshes load as the plain files do, zeros after the
//! last member are padding, and decompression honours its limit, a bomb included.

use gpurt::scene::{self, stl};

use crate::common::inputs::{VIEW, gzip, tetra, write};
use crate::common::temp_dir;

#[test]
fn gzip_inputs_load_like_plain_ones() {
    let dir = temp_dir("gzip");
    let tris = tetra();
    let bin = stl::write_binary(&tris, &[0; 80]);
    let nff_src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\np 4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n");
    let files: [(&str, Vec<u8>); 4] = [
        ("part.stl", bin.clone()),
        ("part.stl.gz", gzip(&bin)),
        ("scene.nff", nff_src.clone().into_bytes()),
        ("scene.nff.gz", gzip(nff_src.as_bytes())),
    ];
    for (name, bytes) in &files {
        write(&dir.join(name), bytes);
    }
    let load = |name: &str| scene::load(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
    let (stl_plain, stl_gz) = (load("part.stl"), load("part.stl.gz"));
    assert_eq!(stl_gz.triangles, tris);
    assert_eq!(stl_gz.triangles, stl_plain.triangles);
    assert_eq!(stl_gz.camera, stl_plain.camera);
    let (nff_plain, nff_gz) = (load("scene.nff"), load("scene.nff.gz"));
    assert_eq!((nff_gz.spheres.len(), nff_gz.triangles.len()), (1, 2));
    assert_eq!(nff_gz.triangles, nff_plain.triangles);
    assert_eq!(nff_gz.spheres, nff_plain.spheres);
    // A corrupt gzip stream is an error naming the file.
    let mut bad = gzip(&bin);
    let mid = bad.len() / 2;
    bad.truncate(mid);
    write(&dir.join("bad.stl.gz"), &bad);
    let e = scene::load(&dir.join("bad.stl.gz")).unwrap_err();
    assert!(e.to_string().contains("bad.stl.gz"), "{e}");
}

/// Zero bytes after the last gzip member are padding (`gzip -t` accepts them); other
/// bytes after it are still an error, and a second member is read like the first.
#[test]
fn gzip_padding_with_zeros_is_accepted() {
    let dir = temp_dir("gzip-padding");
    let src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\n");
    let one = gzip(src.as_bytes());
    let cases: [(&str, Vec<u8>, Option<usize>); 3] = [
        (
            "padded.nff.gz",
            [one.clone(), vec![0; 1024]].concat(),
            Some(1),
        ),
        ("two.nff.gz", [one.clone(), one.clone()].concat(), Some(2)),
        (
            "junk.nff.gz",
            [one.clone(), b"junk".to_vec()].concat(),
            None,
        ),
    ];
    for (name, bytes, spheres) in cases {
        write(&dir.join(name), &bytes);
        match (scene::load(&dir.join(name)), spheres) {
            (Ok(s), Some(n)) => assert_eq!(s.spheres.len(), n, "{name}"),
            (Err(e), None) => assert!(e.to_string().contains(name), "{e}"),
            (r, _) => panic!("{name}: {:?}", r.map(|s| s.spheres.len())),
        }
    }
}

/// `decompress` is the one home of the gzip handling `read_file` does: the same bytes for
/// a file and for its contents, plain bytes passed through, and output past the limit an
/// error naming the file (the fuzz target runs it with a small limit).
#[test]
fn decompress_is_what_read_file_does_and_honours_its_limit() {
    let dir = temp_dir("decompress");
    let src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\n");
    let gz = [gzip(src.as_bytes()), gzip(b"# second member\n")].concat();
    let path = dir.join("scene.nff.gz");
    write(&path, &gz);
    let read = scene::io::read_file(&path).unwrap();
    assert_eq!(read, [src.as_bytes(), b"# second member\n"].concat());
    assert_eq!(
        scene::io::decompress(gz.clone(), &path, gpurt::limits::MAX_FILE_BYTES).unwrap(),
        read
    );
    let plain = src.clone().into_bytes();
    assert_eq!(
        scene::io::decompress(plain.clone(), &path, 4).unwrap(),
        plain
    );
    // Exactly the limit is fine; one byte more is not.
    let n = read.len() as u64;
    assert_eq!(scene::io::decompress(gz.clone(), &path, n).unwrap(), read);
    let e = scene::io::decompress(gz.clone(), &path, n - 1).unwrap_err();
    let shown = e.to_string();
    assert!(
        shown.contains("scene.nff.gz") && shown.contains(&format!("more than {} bytes", n - 1)),
        "{shown}"
    );
    // A bomb: a megabyte of zeros in about a kilobyte, refused at 64 KiB.
    let bomb = gzip(&vec![0; 1 << 20]);
    assert!(bomb.len() < 8192, "{}", bomb.len());
    assert!(scene::io::decompress(bomb, &path, 64 << 10).is_err());
    // Zeros after the last member are padding, for `decompress` as for `read_file`;
    // bytes after the padding are not.
    let padded = [gz.clone(), vec![0; 5000]].concat();
    assert_eq!(
        scene::io::decompress(padded.clone(), &path, n).unwrap(),
        read
    );
    let junk = [padded, b"x".to_vec()].concat();
    assert!(scene::io::decompress(junk, &path, n).is_err());
}
