//! A port's part of the generated glue: its handle as the codels see it (`{c}_p` of the
//! header), a `#[repr(C)]` struct of the functions the glue gives, and its one static
//! value. A simple port's data is a field of the module object's state; a `multiple`
//! port's are its instances by name (`bip_genom_c::Instances`), each function taking the
//! instance's name first, as GenoM3's C mapping has it.
//!
//! `data` points into the state (NULL for an instance that is not open); an out port's
//! `write` hands a copy to the engine's port (one port in the model, one age for every
//! instance: the engine's data is the instance written last); an in port's `read` copies
//! the engine's data of the port it is connected to (none yet leaves it as it was; a
//! multiple in port's instance is opened by its first read), and fails with
//! `genom_syserr` ENOTCONN for a port connected to nothing; `open` and `close` of a
//! multiple out port make and drop an instance (closing one that is not open, or writing
//! it, fails with ENOENT). A NULL instance name fails with EINVAL.

use std::fmt::Write as _;

use bip_lang::gen3::ast::PortDir;

use super::ctype::{CType, CTypes};
use super::glue_args::{port_field, port_handle, port_handle_type, Conv};
use super::mirror::Mirrors;
use crate::CodegenError;

/// The port a handle is made for.
pub struct Port<'a> {
    pub component: &'a str,
    pub name: &'a str,
    pub dir: PortDir,
    pub multiple: bool,
}

/// A statement that returns `genom_syserr` with the errno of the weak constant `code` of
/// the runtime header (`bip_genom_enotconn`), kept by the context as a throw keeps it.
fn fail(code: &str) -> String {
    format!("let code = unsafe {{ {code} }}.to_ne_bytes();\n        return unsafe {{ bip_genom_c::context::throw(this, core::ptr::addr_of!(genom_syserr_id).cast(), &code) }};")
}

pub fn port_glue(
    out: &mut String,
    m: &mut Mirrors,
    types: &CTypes,
    port: &Port<'_>,
    t: &CType,
    conv: Conv,
) -> Result<(), CodegenError> {
    let (c, name) = (port.component, port.name);
    let rust = m.rust(types, t, 1)?;
    let element = match types.fin(t) {
        CType::String(Some(_)) => "core::ffi::c_char".to_string(),
        CType::Array(e, _) => m.rust(types, e, 1)?,
        _ => rust.clone(),
    };
    let handle = port_handle_type(name);
    let field = port_field(name);
    let state = format!("(*(*call).state).{field}");
    let engine = conv.engine_type(&rust);
    // the instance's name, first of a multiple port's functions
    let (id_param, id_type, name_it) = if port.multiple {
        (
            "id: *const core::ffi::c_char, ",
            "*const core::ffi::c_char, ",
            format!(
                "    if id.is_null() {{\n        {}\n    }}\n    // SAFETY: a codel passes a NUL-terminated name\n    let id = unsafe {{ core::ffi::CStr::from_ptr(id) }};\n",
                fail("bip_genom_einval")
            ),
        )
    } else {
        ("", "", String::new())
    };
    let unconnected = format!(
        "    // connected to nothing: GenoM3's failed read\n    if !unsafe {{ (*(*call).ctx).port_is_connected({c:?}, {name:?}) }} {{\n        {}\n    }}\n",
        fail("bip_genom_enotconn")
    );
    let not_open = fail("bip_genom_enoent");
    let mut verbs: Vec<(&str, String)> = Vec::new();
    let data = if port.multiple {
        format!("match unsafe {{ {state}.get_mut(id) }} {{\n        Some(v) => (v as *mut {rust}).cast(),\n        None => core::ptr::null_mut(),\n    }}")
    } else {
        format!("unsafe {{ core::ptr::addr_of_mut!({state}).cast() }}")
    };
    match (port.dir, port.multiple) {
        (PortDir::Out, false) => verbs.push((
            "write",
            format!(
                "    unsafe {{\n        let v = {};\n        (*(*call).ctx).write_port::<{engine}>({name:?}, v);\n    }}\n",
                conv.to_engine(&state)
            ),
        )),
        (PortDir::Out, true) => {
            verbs.push((
                "write",
                format!(
                    "    let Some(inst) = (unsafe {{ {state}.get(id) }}).map(|v| v as *const {rust}) else {{\n        {not_open}\n    }};\n    unsafe {{\n        let v = {};\n        (*(*call).ctx).write_port::<{engine}>({name:?}, v);\n    }}\n",
                    conv.to_engine("(*inst)")
                ),
            ));
            verbs.push(("open", format!("    unsafe {{ {state}.open(id) }};\n")));
            verbs.push((
                "close",
                format!("    if !unsafe {{ {state}.close(id) }} {{\n        {not_open}\n    }}\n"),
            ));
        }
        (PortDir::In, multiple) => {
            let target = if multiple {
                format!("*{state}.open(id)")
            } else {
                state.clone()
            };
            verbs.push((
                "read",
                format!(
                    "{unconnected}    if let Some(v) = unsafe {{ (*(*call).ctx).port::<{engine}>({c:?}, {name:?}) }} {{\n        let v = {};\n        unsafe {{ {target} = v }};\n    }}\n",
                    conv.to_c("v", &rust)
                ),
            ));
        }
    }

    let members: String = verbs
        .iter()
        .map(|(verb, _)| format!("    {verb}: unsafe extern \"C\" fn({id_type}*const bip_genom_c::ContextIface) -> bip_genom_c::GenomEvent,\n"))
        .collect();
    let values: String = verbs
        .iter()
        .map(|(verb, _)| format!("    {verb}: {field}_{verb},\n"))
        .collect();
    let _ = write!(
        out,
        r#"
/// Port `{name}`'s handle as its codels see it.
#[repr(C)]
pub struct {handle} {{
    data: unsafe extern "C" fn({id_type}*const bip_genom_c::ContextIface) -> *mut {element},
{members}}}

#[allow(non_upper_case_globals)]
static {h}: {handle} = {handle} {{
    data: {field}_data,
{values}}};

unsafe extern "C" fn {field}_data({id_param}this: *const bip_genom_c::ContextIface) -> *mut {element} {{
    // SAFETY: the context a codel passes is its module object's, whose call is a `Call`
    let Some(call) = (unsafe {{ bip_genom_c::context::call::<Call>(this) }}) else {{
        return core::ptr::null_mut();
    }};
{id_only}    {data}
}}
"#,
        h = port_handle(name),
        id_only = if port.multiple {
            "    if id.is_null() {\n        return core::ptr::null_mut();\n    }\n    // SAFETY: a codel passes a NUL-terminated name\n    let id = unsafe { core::ffi::CStr::from_ptr(id) };\n"
        } else {
            ""
        },
    );
    for (verb, body) in &verbs {
        let _ = write!(
            out,
            r#"
#[allow(unused_parens)]
unsafe extern "C" fn {field}_{verb}({id_param}this: *const bip_genom_c::ContextIface) -> bip_genom_c::GenomEvent {{
    // SAFETY: as in `{field}_data`
    let Some(call) = (unsafe {{ bip_genom_c::context::call::<Call>(this) }}) else {{
        return core::ptr::addr_of!(genom_fatal).cast();
    }};
{name_it}{body}    core::ptr::null()
}}
"#
        );
    }
    Ok(())
}
