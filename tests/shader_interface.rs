//! Each pass's Rust declaration against its shader's SPIR-V: for every pass of the hybrid frame
//! (every pass on: `--full`, primary rays, the injected test signal) and of the reference path
//! tracer, the set-1 bindings (binding number, GLSL name, descriptor kind) and the size of the
//! push-constant block must equal what the pass declares (`Pass::shader_interface`: its inputs
//! and outputs and `size_of` its `#[repr(C)]` push struct), for every ray-backend variant of a
//! traced shader. A renamed output, a reordered binding or a push-constant field added on one
//! side fails here rather than as a wrong picture.

mod common;

use hybrid_rt::gpu::{BindingKind, RAY_VARIANTS, ShaderLibrary};
use hybrid_rt::graph::ShaderInterface;
use hybrid_rt::render::{RenderMode, Settings};
use hybrid_rt::scene::builtin;
use spirv::Module;
use std::collections::BTreeMap;

#[test]
fn every_pass_matches_its_shader() {
    let ctx = common::validated_context();
    let shaders = ShaderLibrary::embedded();
    let backend = common::auto_backend(&ctx);
    let base = Settings { width: 16, height: 16, full: true, ..Default::default() };
    let configs = [
        Settings { primary_rays: true, test_signal: true, taa: true, ..base.clone() },
        Settings { mode: RenderMode::Reference { seed: 1, max_bounces: 2 }, ..base },
    ];
    let mut checked = Vec::new();
    for settings in configs {
        let scene = builtin::soft_shadow_test();
        let r = common::renderer(&ctx, scene, settings, backend);
        for (pass, interface) in r.graph.shader_interfaces() {
            for key in variants(&interface.shader) {
                let module = Module::parse(&shaders.get(&key).unwrap()).unwrap_or_else(|e| panic!("{key}: {e}"));
                if let Err(e) = check(&interface, &module) {
                    panic!("pass {pass} against {key}:\n{e}");
                }
                checked.push(key);
            }
        }
    }
    // The passes every frame has, so a graph that silently lost its interfaces fails too.
    for shader in ["gi.comp:compute", "shadows.comp:rayquery", "svgf_atrous.comp", "taa.comp", "pathtrace.comp:compute"]
    {
        assert!(checked.iter().any(|k| k == shader), "{shader} was not checked; checked: {checked:?}");
    }
    common::assert_validation_clean(ctx);
}

/// The module keys of every ray-backend variant of a traced shader (`shadows.comp:compute` ->
/// both), or the key itself.
fn variants(key: &str) -> Vec<String> {
    match key.split_once(':') {
        Some((file, _)) => RAY_VARIANTS.iter().map(|(v, _)| format!("{file}:{v}")).collect(),
        None => vec![key.to_string()],
    }
}

/// Compares one declaration with one module; the error lists every difference.
fn check(rust: &ShaderInterface, module: &Module) -> Result<(), String> {
    let mut problems = Vec::new();
    let glsl: BTreeMap<u32, (String, BindingKind)> =
        module.bindings().into_iter().filter(|b| b.set == 1).map(|b| (b.binding, (b.name, b.kind))).collect();
    for (i, (name, kind)) in rust.bindings.iter().enumerate() {
        match glsl.get(&(i as u32)) {
            None => problems.push(format!("binding {i}: Rust declares {name} ({kind:?}), the shader has none")),
            Some((g_name, g_kind)) if g_name != name || g_kind != kind => problems
                .push(format!("binding {i}: Rust declares {name} ({kind:?}), the shader has {g_name} ({g_kind:?})")),
            Some(_) => {}
        }
    }
    for (b, (name, kind)) in glsl.range(rust.bindings.len() as u32..) {
        problems.push(format!("binding {b}: the shader has {name} ({kind:?}), Rust declares nothing"));
    }
    let push = module.push_constant_size().map_err(|e| e.to_string())?;
    if push != rust.push_constant_size {
        problems.push(format!(
            "push constants: the shader's block is {push} bytes, the Rust struct {} bytes",
            rust.push_constant_size
        ));
    }
    if problems.is_empty() { Ok(()) } else { Err(problems.join("\n")) }
}

/// The few SPIR-V instructions a shader's interface is made of (SPIR-V spec 1.6, section 3).
mod spirv {
    use hybrid_rt::gpu::BindingKind;
    use std::collections::HashMap;

    const MAGIC: u32 = 0x0723_0203;
    // Opcodes.
    const OP_NAME: u32 = 5;
    const OP_TYPE_INT: u32 = 21;
    const OP_TYPE_FLOAT: u32 = 22;
    const OP_TYPE_VECTOR: u32 = 23;
    const OP_TYPE_IMAGE: u32 = 25;
    const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
    const OP_TYPE_ARRAY: u32 = 28;
    const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
    const OP_TYPE_STRUCT: u32 = 30;
    const OP_TYPE_POINTER: u32 = 32;
    const OP_VARIABLE: u32 = 59;
    const OP_DECORATE: u32 = 71;
    const OP_MEMBER_DECORATE: u32 = 72;
    const OP_TYPE_ACCELERATION_STRUCTURE: u32 = 5341;
    // Decorations.
    const BLOCK: u32 = 2;
    const BUFFER_BLOCK: u32 = 3;
    const BINDING: u32 = 33;
    const DESCRIPTOR_SET: u32 = 34;
    const OFFSET: u32 = 35;
    // Storage classes.
    const UNIFORM: u32 = 2;
    const PUSH_CONSTANT: u32 = 9;
    const STORAGE_BUFFER: u32 = 12;

    /// A type, as far as bindings and push constants need one.
    enum Type {
        Scalar(usize),
        Vector(u32, usize),
        /// Sampled: 1 = used with a sampler, 2 = a storage image.
        Image(u32),
        SampledImage,
        Array(u32),
        Struct(Vec<u32>),
        /// A pointer's pointee type.
        Pointer(u32),
        AccelerationStructure,
    }

    pub struct Binding {
        pub set: u32,
        pub binding: u32,
        pub name: String,
        pub kind: BindingKind,
    }

    #[derive(Default)]
    pub struct Module {
        names: HashMap<u32, String>,
        types: HashMap<u32, Type>,
        /// (id, pointer type, storage class)
        variables: Vec<(u32, u32, u32)>,
        decorations: HashMap<(u32, u32), u32>,
        member_offsets: HashMap<(u32, u32), u32>,
    }

    impl Module {
        pub fn parse(words: &[u32]) -> Result<Self, String> {
            if words.len() < 5 || words[0] != MAGIC {
                return Err("not SPIR-V (bad magic)".into());
            }
            let mut m = Module::default();
            let mut at = 5;
            while at < words.len() {
                let (count, op) = ((words[at] >> 16) as usize, words[at] & 0xffff);
                if count == 0 || at + count > words.len() {
                    return Err(format!("truncated instruction at word {at}"));
                }
                let w = &words[at + 1..at + count];
                match op {
                    OP_NAME => {
                        m.names.insert(w[0], string(&w[1..]));
                    }
                    OP_TYPE_INT | OP_TYPE_FLOAT => {
                        m.types.insert(w[0], Type::Scalar(w[1] as usize / 8));
                    }
                    OP_TYPE_VECTOR => {
                        m.types.insert(w[0], Type::Vector(w[1], w[2] as usize));
                    }
                    OP_TYPE_IMAGE => {
                        m.types.insert(w[0], Type::Image(w[6]));
                    }
                    OP_TYPE_SAMPLED_IMAGE => {
                        m.types.insert(w[0], Type::SampledImage);
                    }
                    OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY => {
                        m.types.insert(w[0], Type::Array(w[1]));
                    }
                    OP_TYPE_STRUCT => {
                        m.types.insert(w[0], Type::Struct(w[1..].to_vec()));
                    }
                    OP_TYPE_POINTER => {
                        m.types.insert(w[0], Type::Pointer(w[2]));
                    }
                    OP_TYPE_ACCELERATION_STRUCTURE => {
                        m.types.insert(w[0], Type::AccelerationStructure);
                    }
                    OP_VARIABLE => m.variables.push((w[1], w[0], w[2])),
                    OP_DECORATE => {
                        m.decorations.insert((w[0], w[1]), w.get(2).copied().unwrap_or(0));
                    }
                    OP_MEMBER_DECORATE if w[2] == OFFSET => {
                        m.member_offsets.insert((w[0], w[1]), w[3]);
                    }
                    _ => {}
                }
                at += count;
            }
            Ok(m)
        }

        /// Every descriptor binding: its set, number, GLSL name (the block's name for an
        /// anonymous buffer block) and kind.
        pub fn bindings(&self) -> Vec<Binding> {
            let mut out = Vec::new();
            for &(id, pointer, class) in &self.variables {
                let (Some(&set), Some(&binding)) =
                    (self.decorations.get(&(id, DESCRIPTOR_SET)), self.decorations.get(&(id, BINDING)))
                else {
                    continue;
                };
                let Some(&Type::Pointer(mut ty)) = self.types.get(&pointer) else { continue };
                while let Some(Type::Array(element)) = self.types.get(&ty) {
                    ty = *element;
                }
                let kind = match (self.types.get(&ty), class) {
                    (Some(Type::Image(2)), _) => BindingKind::StorageImage,
                    (Some(Type::Image(_) | Type::SampledImage), _) => BindingKind::SampledImage,
                    (Some(Type::AccelerationStructure), _) => BindingKind::AccelerationStructure,
                    (_, STORAGE_BUFFER) => BindingKind::StorageBuffer,
                    (_, UNIFORM) if self.decorations.contains_key(&(ty, BUFFER_BLOCK)) => BindingKind::StorageBuffer,
                    (_, UNIFORM) if self.decorations.contains_key(&(ty, BLOCK)) => BindingKind::UniformBuffer,
                    _ => continue,
                };
                let name = match self.names.get(&id).filter(|n| !n.is_empty()) {
                    Some(n) => n.clone(),
                    None => self.names.get(&ty).cloned().unwrap_or_default(),
                };
                out.push(Binding { set, binding, name, kind });
            }
            out
        }

        /// Bytes of the push-constant block (0 without one): its last member's offset and size.
        pub fn push_constant_size(&self) -> Result<usize, String> {
            let Some(&(_, pointer, _)) = self.variables.iter().find(|v| v.2 == PUSH_CONSTANT) else { return Ok(0) };
            let Some(Type::Pointer(block)) = self.types.get(&pointer) else { return Err("bad pointer".into()) };
            self.size_of(*block)
        }

        fn size_of(&self, ty: u32) -> Result<usize, String> {
            match self.types.get(&ty) {
                Some(Type::Scalar(bytes)) => Ok(*bytes),
                Some(Type::Vector(component, n)) => Ok(self.size_of(*component)? * n),
                Some(Type::Struct(members)) => {
                    let mut end = 0;
                    for (i, member) in members.iter().enumerate() {
                        let offset = self.member_offsets.get(&(ty, i as u32)).ok_or("member without an Offset")?;
                        end = end.max(*offset as usize + self.size_of(*member)?);
                    }
                    Ok(end)
                }
                _ => Err(format!("push constants: type %{ty} is not a scalar, vector or struct")),
            }
        }
    }

    /// A literal string: UTF-8, nul-terminated, packed into words.
    fn string(words: &[u32]) -> String {
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
        String::from_utf8_lossy(&bytes).into_owned()
    }
}
