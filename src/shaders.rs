//! WGSL assembly: the files under `shaders/`, embedded in the binary, joined by a tiny
//! `#import` resolver, and validated with naga (in a plain `cargo test`, no GPU needed).
//! One concept: the shader table and its assembly and, below them, the tests that hold
//! every shader to the conventions (validation, variants, headers, twins).
//!
//! A kernel file imports shared modules one per line:
//!
//! ```wgsl
//! #import shared/bvh
//! ```
//!
//! [`assemble`] replaces each such line by the module's text, recursively, each module at
//! most once. A kernel variant is chosen with aliases: importing `shared/vec16` with the
//! alias `("shared/vec16", "shared/vec16_subgroup")` pulls in the subgroup implementation.
//!
//! ```
//! let wgsl = penumbra::shaders::assemble("gpu_selftest", &[])?;
//! penumbra::shaders::validate(&wgsl)?;
//! # Ok::<(), String>(())
//! ```

use naga::valid::{Capabilities, ValidationFlags, Validator};

/// Every WGSL file under `shaders/`, as `(import name, source)`; the name is the path
/// inside `shaders/` without `.wgsl` (`shared/bvh` is `shaders/shared/bvh.wgsl`).
///
/// Adding a shader: put the file under `shaders/`, add its line here (sorted), and list it
/// in [`KERNELS`] if it has an entry point. A test checks that this table and the folder agree.
pub static SOURCES: &[(&str, &str)] = &[
    ("filter", include_str!("../shaders/filter.wgsl")),
    (
        "gbuffer_from_depth",
        include_str!("../shaders/gbuffer_from_depth.wgsl"),
    ),
    (
        "gbuffer_from_position",
        include_str!("../shaders/gbuffer_from_position.wgsl"),
    ),
    ("gpu_selftest", include_str!("../shaders/gpu_selftest.wgsl")),
    ("primary", include_str!("../shaders/primary.wgsl")),
    ("primary_mft", include_str!("../shaders/primary_mft.wgsl")),
    ("refine_gather", include_str!("../shaders/refine_gather.wgsl")),
    ("refine_resolve", include_str!("../shaders/refine_resolve.wgsl")),
    ("refine_select", include_str!("../shaders/refine_select.wgsl")),
    ("shade", include_str!("../shaders/shade.wgsl")),
    ("shadow_mft", include_str!("../shaders/shadow_mft.wgsl")),
    ("shadow_packet", include_str!("../shaders/shadow_packet.wgsl")),
    ("shadow_per_ray", include_str!("../shaders/shadow_per_ray.wgsl")),
    (
        "shadow_ray_query",
        include_str!("../shaders/shadow_ray_query.wgsl"),
    ),
    ("shared/alpha", include_str!("../shaders/shared/alpha.wgsl")),
    (
        "shared/alpha_none",
        include_str!("../shaders/shared/alpha_none.wgsl"),
    ),
    (
        "shared/alpha_words",
        include_str!("../shaders/shared/alpha_words.wgsl"),
    ),
    ("shared/bvh", include_str!("../shaders/shared/bvh.wgsl")),
    (
        "shared/bvh_vec16",
        include_str!("../shaders/shared/bvh_vec16.wgsl"),
    ),
    ("shared/counters", include_str!("../shaders/shared/counters.wgsl")),
    ("shared/descend", include_str!("../shaders/shared/descend.wgsl")),
    ("shared/groups", include_str!("../shaders/shared/groups.wgsl")),
    (
        "shared/filter_window",
        include_str!("../shaders/shared/filter_window.wgsl"),
    ),
    (
        "shared/intersect",
        include_str!("../shaders/shared/intersect.wgsl"),
    ),
    ("shared/layout", include_str!("../shaders/shared/layout.wgsl")),
    (
        "shared/pixel_rays",
        include_str!("../shaders/shared/pixel_rays.wgsl"),
    ),
    ("shared/primary", include_str!("../shaders/shared/primary.wgsl")),
    ("shared/refine", include_str!("../shaders/shared/refine.wgsl")),
    ("shared/surface", include_str!("../shaders/shared/surface.wgsl")),
    ("shared/suspend", include_str!("../shaders/shared/suspend.wgsl")),
    (
        "shared/vec16_subgroup",
        include_str!("../shaders/shared/vec16_subgroup.wgsl"),
    ),
    (
        "shared/vec16_workgroup",
        include_str!("../shaders/shared/vec16_workgroup.wgsl"),
    ),
    (
        "visibility_to_texture",
        include_str!("../shaders/visibility_to_texture.wgsl"),
    ),
    (
        "visibility_values",
        include_str!("../shaders/visibility_values.wgsl"),
    ),
];

/// An alias set: `(import name, module to use instead)`.
pub type Aliases<'a> = &'a [(&'a str, &'a str)];

/// The alias of the shadow kernels' build without the alpha binding
/// ([`crate::gpu::kernel::AlphaKernels`]).
pub const NO_ALPHA: (&str, &str) = ("shared/alpha_words", "shared/alpha_none");

/// Every kernel (a top-level file of [`SOURCES`]) with the alias sets of all its variants;
/// `cargo test` assembles and validates each one. A kernel without variants has one empty set.
pub const KERNELS: &[(&str, &[Aliases<'static>])] = &[
    ("filter", &[&[]]),
    ("gbuffer_from_depth", &[&[]]),
    ("gbuffer_from_position", &[&[]]),
    ("gpu_selftest", &[&[]]),
    ("primary", &[&[]]),
    (
        "primary_mft",
        &[
            &[("shared/vec16", "shared/vec16_subgroup")],
            &[("shared/vec16", "shared/vec16_workgroup")],
        ],
    ),
    ("refine_gather", &[&[]]),
    ("refine_resolve", &[&[]]),
    ("refine_select", &[&[]]),
    ("shade", &[&[]]),
    (
        "shadow_mft",
        &[
            &[("shared/vec16", "shared/vec16_subgroup")],
            &[("shared/vec16", "shared/vec16_workgroup")],
            &[("shared/vec16", "shared/vec16_subgroup"), NO_ALPHA],
            &[("shared/vec16", "shared/vec16_workgroup"), NO_ALPHA],
        ],
    ),
    (
        "shadow_packet",
        &[
            &[("shared/vec16", "shared/vec16_subgroup")],
            &[("shared/vec16", "shared/vec16_workgroup")],
            &[("shared/vec16", "shared/vec16_subgroup"), NO_ALPHA],
            &[("shared/vec16", "shared/vec16_workgroup"), NO_ALPHA],
        ],
    ),
    ("shadow_per_ray", &[&[], &[NO_ALPHA]]),
    ("shadow_ray_query", &[&[]]),
    ("visibility_to_texture", &[&[]]),
    ("visibility_values", &[&[]]),
];

/// What [`validate`] allows beyond core WGSL: exactly what [`crate::gpu::GpuContext`] may
/// enable (subgroup operations; ray queries, which only the `shadow_ray_query` kernel
/// uses and only a device with them builds), plus naga's defaults that every wgpu
/// backend we use has.
pub const VALIDATION_CAPABILITIES: Capabilities = Capabilities::MULTISAMPLED_SHADING
    .union(Capabilities::CUBE_ARRAY_TEXTURES)
    .union(Capabilities::SUBGROUP)
    .union(Capabilities::RAY_QUERY);

/// The source of the module `name` (e.g. `"shared/bvh"`), if there is one.
pub fn source(name: &str) -> Option<&'static str> {
    lookup(SOURCES, name)
}

/// The text of kernel `main` with every `#import NAME` line replaced by module `NAME`
/// (after `aliases`), recursively, each module included once.
///
/// Errors (as text naming the file and line): unknown `main`, unknown import, import cycle,
/// a malformed `#import` line.
pub fn assemble(main: &str, aliases: Aliases<'_>) -> Result<String, String> {
    assemble_from(SOURCES, main, aliases)
}

/// Parses and validates assembled WGSL with naga; on failure returns naga's own
/// diagnostics (with source excerpts) as text.
pub fn validate(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    Validator::new(ValidationFlags::all(), VALIDATION_CAPABILITIES)
        .validate(&module)
        .map_err(|e| e.emit_to_string(source))?;
    Ok(module)
}

fn lookup<'t>(table: &[(&str, &'t str)], name: &str) -> Option<&'t str> {
    table.iter().find(|(n, _)| *n == name).map(|&(_, text)| text)
}

/// [`assemble`] over any table of sources, so the resolver is testable with inline modules.
fn assemble_from(table: &[(&str, &str)], main: &str, aliases: Aliases<'_>) -> Result<String, String> {
    let text = lookup(table, main).ok_or_else(|| {
        format!(
            "no shader named `{main}` (known: {})",
            table.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
        )
    })?;
    let mut assembler = Assembler {
        table,
        aliases,
        included: Vec::new(),
        stack: Vec::new(),
        out: String::with_capacity(text.len()),
    };
    assembler.expand(main, text)?;
    Ok(assembler.out)
}

struct Assembler<'a> {
    table: &'a [(&'a str, &'a str)],
    aliases: Aliases<'a>,
    /// Modules already pasted in (or being pasted in): later imports of them are skipped.
    included: Vec<String>,
    /// The chain of files being expanded, to report a cycle as `a → b → a`.
    stack: Vec<String>,
    out: String,
}

impl Assembler<'_> {
    fn expand(&mut self, name: &str, text: &str) -> Result<(), String> {
        self.stack.push(name.to_owned());
        self.included.push(name.to_owned());
        for (line_ix, line) in text.lines().enumerate() {
            let import = match parse_import(line) {
                None => {
                    self.out.push_str(line);
                    self.out.push('\n');
                    continue;
                }
                Some(Err(message)) => {
                    return Err(format!("shaders/{name}.wgsl line {}: {message}", line_ix + 1));
                }
                Some(Ok(import)) => import,
            };
            let target = self
                .aliases
                .iter()
                .find(|(from, _)| *from == import)
                .map_or(import, |&(_, to)| to);
            if self.stack.iter().any(|s| s == target) {
                let mut chain = self.stack.join(" → ");
                chain.push_str(" → ");
                chain.push_str(target);
                return Err(format!("import cycle: {chain}"));
            }
            let via = if target == import {
                String::new()
            } else {
                format!(" as {target}")
            };
            if self.included.iter().any(|s| s == target) {
                self.out
                    .push_str(&format!("// #import {import}{via}: already included above\n"));
                continue;
            }
            let Some(module) = lookup(self.table, target) else {
                let alias_note = if target == import {
                    String::new()
                } else {
                    format!(" (the alias of `{import}`)")
                };
                return Err(format!(
                    "shaders/{name}.wgsl line {}: `#import {import}`: no shader module named \
                     `{target}`{alias_note}",
                    line_ix + 1
                ));
            };
            self.out.push_str(&format!(
                "// ---- #import {import}{via} (shaders/{target}.wgsl) ----\n"
            ));
            self.expand(target, module)?;
            self.out.push_str(&format!("// ---- end of {target} ----\n"));
        }
        self.stack.pop();
        Ok(())
    }
}

/// `None` for an ordinary line; for an `#import` line, the module name or what is wrong.
fn parse_import(line: &str) -> Option<Result<&str, String>> {
    let rest = line.trim_start().strip_prefix("#import")?;
    if !rest.is_empty() && !rest.starts_with(char::is_whitespace) {
        return Some(Err(format!("malformed import line `{}`", line.trim())));
    }
    let mut words = rest.trim().splitn(2, char::is_whitespace);
    let name = words.next().unwrap_or_default();
    let trailing = words.next().unwrap_or_default().trim();
    if name.is_empty() {
        return Some(Err("`#import` without a module name".to_owned()));
    }
    if !trailing.is_empty() && !trailing.starts_with("//") {
        return Some(Err(format!(
            "`#import {name}` is followed by `{trailing}`; one module per line"
        )));
    }
    Some(Ok(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &[(&str, &str)] = &[
        (
            "main",
            "// main\n#import shared/a\n#import shared/b\nfn main_fn() {}\n",
        ),
        ("shared/a", "// a\n#import shared/c\nfn a() {}\n"),
        ("shared/b", "// b\n#import shared/c\nfn b() {}\n"),
        ("shared/c", "fn c() {}\n"),
        ("shared/c_fast", "fn c() { /* fast */ }\n"),
        ("loop_main", "#import shared/x\n"),
        ("shared/x", "#import shared/y\n"),
        ("shared/y", "#import shared/x\n"),
        ("self_import", "#import self_import\n"),
        ("bad", "fn f() {}\n#import shared/nope\n"),
        ("bad_alias", "#import shared/c\n"),
        ("commented", "  #import shared/c // the c module\n"),
        ("two_on_a_line", "#import shared/a shared/b\n"),
        ("no_name", "#import\n"),
    ];

    fn code_lines(text: &str) -> Vec<&str> {
        text.lines().filter(|l| !l.starts_with("//")).collect()
    }

    #[test]
    fn imports_are_pasted_in_place_recursively_and_once() {
        let out = assemble_from(SAMPLE, "main", &[]).unwrap();
        assert_eq!(
            code_lines(&out),
            ["fn c() {}", "fn a() {}", "fn b() {}", "fn main_fn() {}"]
        );
        assert!(
            out.lines().all(|l| parse_import(l).is_none()),
            "no import line survives:\n{out}"
        );
        assert_eq!(
            out.matches("fn c()").count(),
            1,
            "shared/c is included once:\n{out}"
        );
    }

    #[test]
    fn aliases_choose_the_variant() {
        let out = assemble_from(SAMPLE, "main", &[("shared/c", "shared/c_fast")]).unwrap();
        assert_eq!(
            code_lines(&out),
            [
                "fn c() { /* fast */ }",
                "fn a() {}",
                "fn b() {}",
                "fn main_fn() {}"
            ]
        );
        assert!(out.contains("#import shared/c as shared/c_fast"), "{out}");
    }

    #[test]
    fn trailing_comment_and_indent_are_allowed() {
        let out = assemble_from(SAMPLE, "commented", &[]).unwrap();
        assert_eq!(code_lines(&out), ["fn c() {}"]);
    }

    #[test]
    fn cycles_are_errors() {
        let err = assemble_from(SAMPLE, "loop_main", &[]).unwrap_err();
        assert_eq!(err, "import cycle: loop_main → shared/x → shared/y → shared/x");
        let err = assemble_from(SAMPLE, "self_import", &[]).unwrap_err();
        assert!(err.contains("import cycle: self_import → self_import"), "{err}");
    }

    #[test]
    fn unknown_import_names_module_and_importer() {
        let err = assemble_from(SAMPLE, "bad", &[]).unwrap_err();
        assert!(err.contains("shaders/bad.wgsl line 2"), "{err}");
        assert!(err.contains("shared/nope"), "{err}");
        let err = assemble_from(SAMPLE, "bad_alias", &[("shared/c", "shared/c_missing")]).unwrap_err();
        assert!(err.contains("shaders/bad_alias.wgsl line 1"), "{err}");
        assert!(
            err.contains("`shared/c_missing` (the alias of `shared/c`)"),
            "{err}"
        );
    }

    #[test]
    fn unknown_main_and_malformed_lines_are_errors() {
        let err = assemble_from(SAMPLE, "nope", &[]).unwrap_err();
        assert!(err.contains("no shader named `nope`"), "{err}");
        let err = assemble_from(SAMPLE, "two_on_a_line", &[]).unwrap_err();
        assert!(err.contains("one module per line"), "{err}");
        let err = assemble_from(SAMPLE, "no_name", &[]).unwrap_err();
        assert!(err.contains("without a module name"), "{err}");
    }

    #[test]
    fn validate_returns_naga_diagnostics() {
        let err = validate("fn f() -> u32 { return 1.5; }").unwrap_err();
        // naga's rendered diagnostic: a message plus the source excerpt it points at.
        assert!(err.contains("error"), "{err}");
        assert!(err.contains("return 1.5"), "{err}");
        let err = validate("fn f() { let x: u32 = undefined_thing; }").unwrap_err();
        assert!(err.contains("undefined_thing"), "{err}");
    }

    #[test]
    fn every_shader_variant_validates() {
        let mut failures = Vec::new();
        for &(main, variants) in KERNELS {
            assert!(
                !variants.is_empty(),
                "kernel {main} lists no variants; give it one empty alias set"
            );
            for &aliases in variants {
                let result = assemble(main, aliases).and_then(|wgsl| validate(&wgsl).map(|_| ()));
                if let Err(e) = result {
                    failures.push(format!("kernel {main} with aliases {aliases:?}:\n{e}"));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    }

    #[test]
    fn kernels_have_an_entry_point_named_main() {
        for &(name, variants) in KERNELS {
            let module = validate(&assemble(name, variants[0]).unwrap()).unwrap();
            assert!(
                module.entry_points.iter().any(|e| e.name == "main"),
                "kernel {name} has no entry point `main`"
            );
        }
    }

    #[test]
    fn shadow_kernel_has_the_overrides_the_pass_sets() {
        // ShadowTracer sets these by name; a rename would only fail at pipeline creation.
        for &aliases in KERNELS.iter().find(|(k, _)| *k == "shadow_mft").unwrap().1 {
            let module = validate(&assemble("shadow_mft", aliases).unwrap()).unwrap();
            let leaf = module
                .overrides
                .iter()
                .find(|(_, o)| o.name.as_deref() == Some("LEAF_TRANSPOSED"))
                .map(|(_, o)| &module.types[o.ty].inner);
            assert_eq!(
                leaf,
                Some(&naga::TypeInner::Scalar(naga::Scalar::BOOL)),
                "shadow_mft with {aliases:?}: `override LEAF_TRANSPOSED: bool`"
            );
        }
    }

    #[test]
    fn primary_kernels_have_the_overrides_the_pass_sets() {
        // PrimaryPass sets these by name; a rename would only fail at pipeline creation.
        for kernel in ["primary", "primary_mft"] {
            for &aliases in KERNELS.iter().find(|(k, _)| *k == kernel).unwrap().1 {
                let module = validate(&assemble(kernel, aliases).unwrap()).unwrap();
                let ty = |name: &str| {
                    module
                        .overrides
                        .iter()
                        .find(|(_, o)| o.name.as_deref() == Some(name))
                        .map(|(_, o)| module.types[o.ty].inner.clone())
                };
                assert_eq!(
                    ty("COUNTERS"),
                    Some(naga::TypeInner::Scalar(naga::Scalar::BOOL)),
                    "{kernel} with {aliases:?}: `override COUNTERS: bool`"
                );
                assert_eq!(
                    ty("ITERATION_BUDGET"),
                    Some(naga::TypeInner::Scalar(naga::Scalar::U32)),
                    "{kernel} with {aliases:?}: `override ITERATION_BUDGET: u32`"
                );
            }
        }
    }

    #[test]
    fn every_top_level_shader_is_a_listed_kernel() {
        for &(name, _) in SOURCES {
            if !name.starts_with("shared/") {
                assert!(
                    KERNELS.iter().any(|&(k, _)| k == name),
                    "shaders/{name}.wgsl is not in shaders::KERNELS, so no test validates it"
                );
            }
        }
    }

    /// Each kernel's opening comment names its CPU twin (`CPU twin: ` and a file of
    /// `src/reference/`), a file named after the kernel (`refine_select` → `refine.rs`, the
    /// family's twin) or one of the listed exceptions; or says `CPU twin: none` with a reason.
    #[test]
    fn every_kernel_names_its_twin_after_itself() {
        // One twin for both ways of making a G-buffer from a host's surface textures.
        const EXCEPTIONS: &[(&str, &str)] = &[
            ("gbuffer_from_depth", "gbuffer_from_surface"),
            ("gbuffer_from_position", "gbuffer_from_surface"),
        ];
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        for &(kernel, _) in KERNELS {
            let opening: String = source(kernel)
                .unwrap()
                .lines()
                .take_while(|l| l.starts_with("//"))
                .map(|l| l.trim_start_matches('/').trim())
                .collect::<Vec<_>>()
                .join(" ");
            let Some((_, rest)) = opening.split_once("CPU twin: ") else {
                panic!("shaders/{kernel}.wgsl: its opening comment names no `CPU twin: `")
            };
            if rest.starts_with("none (") {
                continue;
            }
            let twin = rest
                .strip_prefix("src/reference/")
                .and_then(|r| r.split_once(".rs"))
                .map(|(stem, _)| stem)
                .unwrap_or_else(|| {
                    panic!("shaders/{kernel}.wgsl: `CPU twin: {rest}` is not src/reference/….rs")
                });
            assert!(
                root.join(format!("src/reference/{twin}.rs")).is_file(),
                "shaders/{kernel}.wgsl: src/reference/{twin}.rs does not exist"
            );
            assert!(
                kernel == twin
                    || kernel.starts_with(&format!("{twin}_"))
                    || EXCEPTIONS.contains(&(kernel, twin)),
                "shaders/{kernel}.wgsl: its twin src/reference/{twin}.rs is not named after it"
            );
        }
    }

    #[test]
    fn table_matches_the_shaders_folder() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let mut on_disk = Vec::new();
        let mut dirs = vec![root.clone()];
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == "wgsl") {
                    let rel = path.strip_prefix(&root).unwrap().with_extension("");
                    let name = rel
                        .components()
                        .map(|c| c.as_os_str().to_string_lossy())
                        .collect::<Vec<_>>();
                    on_disk.push(name.join("/"));
                }
            }
        }
        on_disk.sort();
        let mut in_table: Vec<String> = SOURCES.iter().map(|(n, _)| (*n).to_owned()).collect();
        in_table.sort();
        assert_eq!(
            in_table, on_disk,
            "shaders::SOURCES (left) and the files under shaders/ (right) differ"
        );
        for (name, text) in SOURCES {
            let path = root.join(format!("{name}.wgsl"));
            assert_eq!(
                *text,
                std::fs::read_to_string(&path).unwrap(),
                "{name} is embedded from another file"
            );
        }
    }

    #[test]
    fn each_shader_opens_with_what_and_who() {
        // STYLE.md #1: the first two lines say what the file computes and who uses it.
        for (name, text) in SOURCES {
            let mut lines = text.lines();
            let opening = [lines.next(), lines.next()];
            assert!(
                opening.iter().all(|l| l.is_some_and(|l| l.starts_with("// "))),
                "shaders/{name}.wgsl must open with two comment lines (what it computes, who calls it)"
            );
        }
    }
}

#[cfg(test)]
mod vector_uniformity;

#[cfg(test)]
mod vector_group_tests {
    /// With `VEC16_PER_WG = n` (the host's vectors per subgroup), every subgroup-vector
    /// kernel's workgroup is `16 n` invocations once naga resolves the overrides as wgpu
    /// does, so the host's `ceil(units / n)` workgroups cover every vector once.
    #[test]
    fn subgroup_vector_workgroups_hold_vec16_per_wg_vectors() {
        for kernel in ["shadow_packet", "shadow_mft", "primary_mft"] {
            let src = super::assemble(kernel, &[("shared/vec16", "shared/vec16_subgroup")]).unwrap();
            let module = super::validate(&src).unwrap();
            let info = naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                super::VALIDATION_CAPABILITIES,
            )
            .validate(&module)
            .unwrap();
            for n in [1u32, 2, 4] {
                let mut constants = naga::back::PipelineConstants::default();
                constants.insert("VEC16_PER_WG".to_owned(), f64::from(n));
                let (resolved, _) = naga::back::pipeline_constants::process_overrides(
                    &module,
                    &info,
                    Some((naga::ShaderStage::Compute, "main")),
                    &constants,
                )
                .unwrap();
                assert_eq!(
                    resolved.entry_points[0].workgroup_size,
                    [16 * n, 1, 1],
                    "{kernel}, {n} vectors"
                );
            }
        }
    }
}
