//! Layouts of the `#[repr(C)]` structs the renderers upload to the GPU, as the Rust compiler
//! lays them out, so that a test can hold each against the WGSL struct it mirrors (parsed with
//! naga: `tests/gpu_layouts.rs`) instead of a "keep in step" comment.
//!
//! Each crate lists its structs with [`rust_layout!`] in a `#[doc(hidden)] pub fn
//! gpu_layouts()` returning [`GpuLayouts`] (the structs and the WGSL they name), which an
//! algorithm's description hands on (`AlgorithmDescription::gpu_layouts`), so the test walks
//! the registry; the macro fails to compile when a field of the struct is left out.

/// One member of a Rust struct: name, byte offset, byte size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RustMember {
    pub name: &'static str,
    pub offset: usize,
    pub size: usize,
}

/// A `#[repr(C)]` struct as compiled, and the WGSL struct it mirrors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RustLayout {
    /// The Rust type's name.
    pub rust: &'static str,
    /// The WGSL struct it mirrors, as `FILE::STRUCT` (the file beside the crate's sources).
    pub wgsl: &'static str,
    pub size: usize,
    pub members: Vec<RustMember>,
}

/// A crate's GPU structs and the WGSL files they mirror.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GpuLayouts {
    pub structs: Vec<RustLayout>,
    /// Each file named by a struct's `wgsl` (`FILE` of `FILE::STRUCT`), composed as the crate
    /// composes it before compiling, generated declarations aside.
    pub sources: Vec<(&'static str, String)>,
}

impl GpuLayouts {
    /// For a renderer that uploads no struct of its own (the peers).
    pub fn none() -> GpuLayouts {
        GpuLayouts::default()
    }

    /// The composed source of WGSL file `file`.
    pub fn source(&self, file: &str) -> Option<&str> {
        self.sources
            .iter()
            .find(|(f, _)| *f == file)
            .map(|(_, s)| s.as_str())
    }
}

/// Size of the field that `_field` projects to (type inference only; never called).
#[doc(hidden)]
pub fn size_of_field<T, F>(_field: fn(&T) -> &F) -> usize {
    std::mem::size_of::<F>()
}

/// `rust_layout!(Type => "file.wgsl::Struct" { field, field, … })`: the [`RustLayout`] of `Type`.
/// Every field must be listed (a destructuring pattern checks it at compile time).
#[macro_export]
macro_rules! rust_layout {
    ($ty:ident => $wgsl:literal { $($field:ident),* $(,)? }) => {{
        #[allow(dead_code)]
        fn exhaustive(v: $ty) {
            let $ty { $($field: _),* } = v;
        }
        $crate::gpu_layout::RustLayout {
            rust: stringify!($ty),
            wgsl: $wgsl,
            size: ::core::mem::size_of::<$ty>(),
            members: vec![$($crate::gpu_layout::RustMember {
                name: stringify!($field),
                offset: ::core::mem::offset_of!($ty, $field),
                size: $crate::gpu_layout::size_of_field(|v: &$ty| &v.$field),
            }),*],
        }
    }};
}
