//! Test support: a `#[repr(C)]` config struct held to its WGSL twin by the layouts both
//! compilers give them. naga (wgpu's shader compiler) parses the shader and lays the WGSL
//! struct out; `offset_of!` gives the Rust one. [`assert_same_layout!`] compares every
//! member's name, byte offset, scalar kind and count, and the two sizes, so a field renamed,
//! retyped, added, dropped or moved on one side only fails — two fields of one type swapped
//! included, which a comparison of names and types in declaration order would let through.
//! Padding members (names starting with `_`) are left out of the member lists; the sizes
//! still cover them.

use wgpu::naga;

/// One member: its name, its byte offset, and its scalar kind with the number of scalars
/// (`("f32", 4)` for `vec4<f32>` and `[f32; 4]` alike).
pub(crate) type Member = (String, u32, &'static str, u32);

/// The members of WGSL struct `name` in `shader` (padding left out), sorted by offset, and
/// the struct's size in bytes, as naga lays them out.
pub(crate) fn wgsl_layout(shader: &str, name: &str) -> (Vec<Member>, u32) {
    let module = naga::front::wgsl::parse_str(shader)
        .unwrap_or_else(|e| panic!("the shader does not parse: {}", e.emit_to_string(shader)));
    let (members, span) = module
        .types
        .iter()
        .find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => {
                Some((members.clone(), *span))
            }
            _ => None,
        })
        .unwrap_or_else(|| panic!("no struct {name} in the shader"));
    let mut out: Vec<Member> = members
        .iter()
        .filter_map(|m| {
            let member = m.name.clone().unwrap_or_default();
            if member.starts_with('_') {
                return None;
            }
            let (kind, count) = shape(&module, &module.types[m.ty].inner);
            Some((member, m.offset, kind, count))
        })
        .collect();
    out.sort_by_key(|m| m.1);
    (out, span)
}

/// A WGSL type as a scalar kind and a count.
fn shape(module: &naga::Module, inner: &naga::TypeInner) -> (&'static str, u32) {
    let scalar = |s: naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => "f32",
        (naga::ScalarKind::Uint, 4) => "u32",
        (naga::ScalarKind::Sint, 4) => "i32",
        other => panic!("a scalar the configs do not use: {other:?}"),
    };
    match inner {
        naga::TypeInner::Scalar(s) => (scalar(*s), 1),
        naga::TypeInner::Atomic(s) => (scalar(*s), 1),
        naga::TypeInner::Vector { size, scalar: s } => (scalar(*s), *size as u32),
        naga::TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => {
            let (kind, count) = shape(module, &module.types[*base].inner);
            (kind, count * n.get())
        }
        other => panic!("a member type the configs do not use: {other:?}"),
    }
}

/// A Rust field type as a scalar kind and a count, for [`assert_same_layout!`].
pub(crate) trait Scalars {
    const KIND: &'static str;
    const COUNT: u32;
}

impl Scalars for u32 {
    const KIND: &'static str = "u32";
    const COUNT: u32 = 1;
}

impl Scalars for i32 {
    const KIND: &'static str = "i32";
    const COUNT: u32 = 1;
}

impl Scalars for f32 {
    const KIND: &'static str = "f32";
    const COUNT: u32 = 1;
}

impl<T: Scalars, const N: usize> Scalars for [T; N] {
    const KIND: &'static str = T::KIND;
    const COUNT: u32 = T::COUNT * N as u32;
}

/// The kind and count of the field a projection `|s| &s.field` reads.
pub(crate) fn field<S, T: Scalars>(_: fn(&S) -> &T) -> (&'static str, u32) {
    (T::KIND, T::COUNT)
}

/// Asserts that `#[repr(C)]` struct `$ty` and WGSL struct `$wgsl` of `$shader` have the same
/// members (`$field`s, every non-padding field of `$ty`) at the same offsets with the same
/// kinds and counts, and the same size.
macro_rules! assert_same_layout {
    ($ty:ty, $shader:expr, $wgsl:literal, [$($field:ident),* $(,)?]) => {{
        let (wgsl, span) = $crate::gpu::layout::wgsl_layout($shader, $wgsl);
        let mut rust: Vec<$crate::gpu::layout::Member> = vec![$({
            let (kind, count) = $crate::gpu::layout::field(|s: &$ty| &s.$field);
            (
                stringify!($field).to_string(),
                std::mem::offset_of!($ty, $field) as u32,
                kind,
                count,
            )
        }),*];
        rust.sort_by_key(|m| m.1);
        assert_eq!(rust, wgsl, "{} (Rust) against {} (WGSL): name, offset, kind, count", stringify!($ty), $wgsl);
        assert_eq!(std::mem::size_of::<$ty>(), span as usize, "size of {}", stringify!($ty));
    }};
}
pub(crate) use assert_same_layout;
