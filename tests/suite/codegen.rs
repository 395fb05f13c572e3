//! `bip codegen FILE --rust OUT`: the bindings bip-codegen generates, written to a file.

use crate::common::bip;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn codegen_writes_the_rovers_bindings() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out = dir.path().join("rover.rs");
    let o = bip(&[
        "codegen",
        "robots/rover.ron",
        "--rust",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let written = std::fs::read_to_string(&out).expect("written");
    // what a build script writes: the same text, formatted alike
    let system = bip_lang::load_file("robots/rover.ron").expect("loads");
    let library = dir.path().join("library.rs");
    bip_codegen::write_bindings_of(&system, &library).expect("writes");
    assert_eq!(written, std::fs::read_to_string(&library).expect("written"));
    assert!(written.contains("pub enum GoToMove {"), "{written}");
}

#[test]
fn codegen_says_why_it_cannot() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out = dir.path().join("p.rs");
    let o = bip(&[
        "codegen",
        "robots/philosophers.ron",
        "--rust",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("no GenoM layer"),
        "{}",
        text(&o.stderr)
    );
    let o = bip(&[
        "codegen",
        "robots/rover.ron",
        "--rust",
        "/nonexistent/dir/r.rs",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("cannot write /nonexistent/dir/r.rs"),
        "{}",
        text(&o.stderr)
    );
}
