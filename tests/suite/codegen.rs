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

#[test]
fn codegen_writes_a_components_c_headers() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out = dir.path().join("include");
    let o = bip(&[
        "codegen",
        "robots/genom3/loco.gen",
        "-I",
        "robots/genom3/idl",
        "--c",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    for file in ["loco_c_types.h", "acloco.h", "genom3/c/context.h"] {
        assert!(out.join(file).is_file(), "{file} is not written");
    }
    // what a build script writes: the same text
    let spec = bip_lang::read_gen_file(
        std::path::Path::new("robots/genom3/loco.gen"),
        &["robots/genom3/idl".into()],
    )
    .expect("reads");
    let headers = bip_codegen::c_headers(&spec).expect("maps");
    let (_, types) = headers
        .iter()
        .find(|(p, _)| p == "loco_c_types.h")
        .expect("the component's header");
    let written = std::fs::read_to_string(out.join("loco_c_types.h")).expect("written");
    assert_eq!(&written, types);
    assert!(
        written.contains("loco_move_track(const rover_speed *ref, rover_speed *current, bool powered, const genom_context self);"),
        "{written}"
    );
    // and the Rust glue that binds its codels, as a build script writes it
    let glue = std::fs::read_to_string(out.join("loco_c.rs")).expect("the glue is written");
    assert!(glue.contains("fn loco_move_track("), "{glue}");
    assert!(glue.contains("pub fn bind("), "{glue}");

    // without its include folder, the `.gen` file's error, with its place
    let o = bip(&[
        "codegen",
        "robots/genom3/loco.gen",
        "--c",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("cannot find the included file `rover.idl`"),
        "{}",
        text(&o.stderr)
    );
}
