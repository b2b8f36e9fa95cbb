//! A test-only check that every vector operation of the 16-wide kernels runs in control
//! flow that is uniform across the workgroup, and that no ballot comes right after a
//! lane-divergent branch (its predicate is computed branch-free).
//!
//! Why: on a GPU a subgroup holds two or four vectors, and a ballot, broadcast or shuffle
//! is defined only where all of the subgroup's invocations run it together; in the
//! workgroup variant the same calls are barriers, which WGSL allows only in uniform control
//! flow. naga checks barriers, but its analysis takes every local variable for
//! non-uniform and ignores loops left by a lane-divergent `break`, the case that matters
//! most. So this is a small version of WGSL's own analysis over naga's IR, for our kernels.
//!
//! Vector operations: the `shared/vec16` primitives ([`PRIMITIVES`]), any raw subgroup
//! operation or barrier, and every function that calls one. Uniform values: literals,
//! constants, overrides, the uniform buffer, `workgroupUniformLoad`, the results of
//! `group_any` and `group_may` (uniform by their contract), and what is computed from
//! uniform values only, including local variables whose every store is uniform and in
//! uniform control flow. Everything else (private and storage memory, builtins, function
//! arguments, other calls) counts as lane-divergent. Control flow is divergent inside an
//! `if`/`switch` on a divergent value, after a `return` taken under divergent control, and
//! in every pass of a loop that a `break` or `continue` under divergent control may leave.
//! The primitives' own bodies are trusted (each file says why it is safe).
//!
//! Control flow that diverged and joined again (after an `if`) is uniform, as in WGSL,
//! where invocations reconverge. The one stricter rule: a `ballot16` must not directly
//! follow an `if` on a divergent value, which is what `a && b` and `a || b` become in
//! naga's IR; ballot predicates use `&` and `|` instead.

use naga::{Block, Expression, Function, Handle, Module, Statement};
use std::collections::{HashMap, HashSet};

/// The `shared/vec16` functions whose bodies hold the subgroup operations or barriers.
pub const PRIMITIVES: &[&str] = &["ballot16", "group_any", "group_may", "vec16_words"];
/// Primitives whose result is the same across the workgroup.
const UNIFORM_RESULTS: &[&str] = &["group_any", "group_may"];

/// One place where a vector operation runs where it must not.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The function that holds it.
    pub function: String,
    /// What runs there and why it is wrong.
    pub what: String,
}

/// Every violation in `module`'s functions and entry points.
pub fn violations(module: &Module) -> Vec<Violation> {
    let vector_fns = vector_functions(module);
    let mut out = Vec::new();
    let mut check = |name: &str, f: &Function| {
        if PRIMITIVES.contains(&name) {
            return;
        }
        let mut a = Analysis {
            module,
            function: f,
            vector_fns: &vector_fns,
            divergent_locals: HashSet::new(),
            violations: Vec::new(),
        };
        // Locals start uniform; each walk marks those stored divergently, until stable.
        loop {
            let before = a.divergent_locals.len();
            for (h, local) in f.local_variables.iter() {
                if local.init.is_some_and(|e| !a.uniform(e)) {
                    a.divergent_locals.insert(h);
                }
            }
            a.violations.clear();
            a.block(&f.body, false);
            if a.divergent_locals.len() == before {
                break;
            }
        }
        out.extend(a.violations.into_iter().map(|what| Violation {
            function: name.to_owned(),
            what,
        }));
    };
    for (_, f) in module.functions.iter() {
        check(f.name.as_deref().unwrap_or("?"), f);
    }
    for ep in &module.entry_points {
        check(&ep.name, &ep.function);
    }
    out
}

/// The functions that run a vector operation, directly or through a call.
fn vector_functions(module: &Module) -> HashSet<Handle<Function>> {
    let mut set: HashSet<Handle<Function>> = module
        .functions
        .iter()
        .filter(|(_, f)| f.name.as_deref().is_some_and(|n| PRIMITIVES.contains(&n)))
        .map(|(h, _)| h)
        .collect();
    loop {
        let before = set.len();
        for (h, f) in module.functions.iter() {
            if !set.contains(&h) && block_runs_vector_op(&f.body, &set) {
                set.insert(h);
            }
        }
        if set.len() == before {
            return set;
        }
    }
}

fn block_runs_vector_op(block: &Block, set: &HashSet<Handle<Function>>) -> bool {
    block.iter().any(|s| match s {
        Statement::Call { function, .. } => set.contains(function),
        s if is_raw_vector_op(s) => true,
        Statement::Block(b) => block_runs_vector_op(b, set),
        Statement::If { accept, reject, .. } => {
            block_runs_vector_op(accept, set) || block_runs_vector_op(reject, set)
        }
        Statement::Switch { cases, .. } => cases.iter().any(|c| block_runs_vector_op(&c.body, set)),
        Statement::Loop { body, continuing, .. } => {
            block_runs_vector_op(body, set) || block_runs_vector_op(continuing, set)
        }
        _ => false,
    })
}

fn is_raw_vector_op(s: &Statement) -> bool {
    matches!(
        s,
        Statement::SubgroupBallot { .. }
            | Statement::SubgroupGather { .. }
            | Statement::SubgroupCollectiveOperation { .. }
            | Statement::ControlBarrier(_)
            | Statement::MemoryBarrier(_)
            | Statement::WorkGroupUniformLoad { .. }
    )
}

struct Analysis<'m> {
    module: &'m Module,
    function: &'m Function,
    vector_fns: &'m HashSet<Handle<Function>>,
    divergent_locals: HashSet<Handle<naga::LocalVariable>>,
    violations: Vec<String>,
}

/// How a block can end: by a `return` or a loop exit taken under divergent control.
#[derive(Clone, Copy, Default)]
struct Exits {
    divergent_return: bool,
    divergent_loop_exit: bool,
}

impl Analysis<'_> {
    fn name_of(&self, f: Handle<Function>) -> &str {
        self.module.functions[f].name.as_deref().unwrap_or("?")
    }

    /// Whether `e` is the same in every invocation of the workgroup.
    fn uniform(&self, e: Handle<Expression>) -> bool {
        let mut memo = HashMap::new();
        self.uniform_memo(e, &mut memo)
    }

    fn uniform_memo(&self, e: Handle<Expression>, memo: &mut HashMap<Handle<Expression>, bool>) -> bool {
        if let Some(&u) = memo.get(&e) {
            return u;
        }
        let all = |es: &[Handle<Expression>], memo: &mut HashMap<_, _>| {
            es.iter().all(|&x| self.uniform_memo(x, memo))
        };
        use Expression as E;
        let u = match self.function.expressions[e] {
            E::Literal(_) | E::Constant(_) | E::Override(_) | E::ZeroValue(_) => true,
            E::WorkGroupUniformLoadResult { .. } => true,
            E::CallResult(f) => UNIFORM_RESULTS.contains(&self.name_of(f)),
            E::GlobalVariable(g) => {
                matches!(self.module.global_variables[g].space, naga::AddressSpace::Uniform)
            }
            E::LocalVariable(l) => !self.divergent_locals.contains(&l),
            E::Load { pointer } => all(&[pointer], memo),
            E::Compose { ref components, .. } => all(components, memo),
            E::Access { base, index } => all(&[base, index], memo),
            E::AccessIndex { base, .. } => all(&[base], memo),
            E::Splat { value, .. } => all(&[value], memo),
            E::Swizzle { vector, .. } => all(&[vector], memo),
            E::Unary { expr, .. } | E::As { expr, .. } => all(&[expr], memo),
            E::Binary { left, right, .. } => all(&[left, right], memo),
            E::Select {
                condition,
                accept,
                reject,
            } => all(&[condition, accept, reject], memo),
            E::Relational { argument, .. } => all(&[argument], memo),
            E::Math {
                arg,
                arg1,
                arg2,
                arg3,
                ..
            } => {
                let args: Vec<_> = [Some(arg), arg1, arg2, arg3].into_iter().flatten().collect();
                all(&args, memo)
            }
            _ => false,
        };
        memo.insert(e, u);
        u
    }

    /// The local variable a store through `pointer` writes, if any.
    fn local_of(&self, mut pointer: Handle<Expression>) -> Option<Handle<naga::LocalVariable>> {
        loop {
            match self.function.expressions[pointer] {
                Expression::LocalVariable(l) => return Some(l),
                Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => pointer = base,
                _ => return None,
            }
        }
    }

    fn flag(&mut self, divergent: bool, what: impl FnOnce() -> String) {
        if divergent {
            self.violations.push(what());
        }
    }

    /// Walks `block` entered with `divergent` control flow; returns how it may end.
    fn block(&mut self, block: &Block, mut divergent: bool) -> Exits {
        let mut exits = Exits::default();
        // The previous statement was an `if` on a lane-divergent value (e.g. `a && b`).
        let mut after_divergent_if = false;
        for statement in block.iter() {
            let mut this_divergent_if = false;
            match *statement {
                Statement::Emit(_) => {
                    // Emitting expressions runs nothing: keep what came before.
                    continue;
                }
                Statement::Call {
                    function,
                    ref arguments,
                    result,
                } => {
                    if self.vector_fns.contains(&function) {
                        let name = self.name_of(function).to_owned();
                        self.flag(divergent, || {
                            format!("`{name}` called in lane-divergent control flow")
                        });
                        self.flag(after_divergent_if && name == "ballot16", || {
                            format!("`{name}` called right after a lane-divergent branch")
                        });
                    }
                    let _ = (arguments, result);
                }
                ref s if is_raw_vector_op(s) => {
                    self.flag(divergent, || format!("{s:?} in lane-divergent control flow"));
                }
                Statement::Store { pointer, value } => {
                    if let Some(l) = self.local_of(pointer)
                        && (divergent || !self.uniform(value) || !self.uniform_pointer(pointer))
                    {
                        self.divergent_locals.insert(l);
                    }
                }
                Statement::Block(ref b) => {
                    let e = self.block(b, divergent);
                    exits = merge(exits, e);
                    divergent |= e.divergent_return || e.divergent_loop_exit;
                }
                Statement::If {
                    condition,
                    ref accept,
                    ref reject,
                } => {
                    let inner = divergent || !self.uniform(condition);
                    this_divergent_if = inner && !divergent;
                    let e = merge(self.block(accept, inner), self.block(reject, inner));
                    exits = merge(exits, e);
                    divergent |= e.divergent_return || e.divergent_loop_exit;
                }
                Statement::Switch { selector, ref cases } => {
                    let inner = divergent || !self.uniform(selector);
                    for case in cases {
                        let e = self.block(&case.body, inner);
                        exits = merge(exits, e);
                        divergent |= e.divergent_return || e.divergent_loop_exit;
                    }
                }
                Statement::Loop {
                    ref body,
                    ref continuing,
                    break_if,
                } => {
                    let mark = self.violations.len();
                    let mut e = self.loop_pass(body, continuing, break_if, divergent);
                    if e.divergent_loop_exit && !divergent {
                        // Later passes run with fewer invocations: check them as divergent.
                        self.violations.truncate(mark);
                        e = self.loop_pass(body, continuing, break_if, true);
                    }
                    exits.divergent_return |= e.divergent_return;
                    divergent |= e.divergent_return;
                }
                Statement::Break | Statement::Continue => {
                    exits.divergent_loop_exit |= divergent;
                }
                Statement::Return { .. } | Statement::Kill => {
                    exits.divergent_return |= divergent;
                }
                _ => {}
            }
            after_divergent_if = this_divergent_if;
        }
        exits
    }

    fn loop_pass(
        &mut self,
        body: &Block,
        continuing: &Block,
        break_if: Option<Handle<Expression>>,
        divergent: bool,
    ) -> Exits {
        let e = self.block(body, divergent);
        let continuing_divergent = divergent || e.divergent_loop_exit || e.divergent_return;
        let c = self.block(continuing, continuing_divergent);
        let mut exits = merge(e, c);
        if break_if.is_some_and(|b| !self.uniform(b)) {
            exits.divergent_loop_exit = true;
        }
        exits
    }

    /// A pointer whose target is the same for every invocation (its indices are uniform).
    fn uniform_pointer(&self, pointer: Handle<Expression>) -> bool {
        match self.function.expressions[pointer] {
            Expression::LocalVariable(_) => true,
            Expression::Access { base, index } => self.uniform_pointer(base) && self.uniform(index),
            Expression::AccessIndex { base, .. } => self.uniform_pointer(base),
            _ => false,
        }
    }
}

fn merge(a: Exits, b: Exits) -> Exits {
    Exits {
        divergent_return: a.divergent_return || b.divergent_return,
        divergent_loop_exit: a.divergent_loop_exit || b.divergent_loop_exit,
    }
}

#[cfg(test)]
mod tests {
    use super::violations;

    /// The vector kernels in both variants.
    const VECTOR_KERNELS: &[&str] = &["shadow_mft", "shadow_packet", "primary_mft"];
    const VARIANTS: &[&str] = &["shared/vec16_subgroup", "shared/vec16_workgroup"];

    #[test]
    fn every_vector_operation_runs_in_uniform_control_flow() {
        for kernel in VECTOR_KERNELS {
            for variant in VARIANTS {
                let src = crate::shaders::assemble(kernel, &[("shared/vec16", variant)]).unwrap();
                let module = crate::shaders::validate(&src).unwrap();
                let found = violations(&module);
                assert!(found.is_empty(), "{kernel} with {variant}: {found:#?}");
            }
        }
    }

    /// A kernel around one statement, on the subgroup primitives.
    fn check(body: &str) -> Vec<super::Violation> {
        let prelude = crate::shaders::source("shared/vec16_subgroup").unwrap();
        let src = format!(
            "{prelude}\n@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n\
             @compute @workgroup_size(VEC16_WG_SIZE)\nfn main(ids: Vec16Ids) {{\n\
             vec16_init(ids);\nvar running = g_lane < 3u;\nvar n = 0u;\n{body}\n}}\n"
        );
        let module = crate::shaders::validate(&src).unwrap_or_else(|e| panic!("{e}\n{src}"));
        violations(&module)
    }

    /// Whether `check(body)` reports `what` (and only that kind of violation).
    fn reports(body: &str, what: &str) -> bool {
        let found = check(body);
        !found.is_empty() && found.iter().all(|v| v.what.contains(what))
    }

    #[test]
    fn the_check_finds_each_kind_of_divergence() {
        const IN_DIVERGENT_FLOW: &str = "called in lane-divergent control flow";
        // Under a lane's own branch.
        assert!(reports(
            "if running { out[0] = ballot16(true); }",
            IN_DIVERGENT_FLOW
        ));
        // Right after one: `&&` is a branch in naga's IR.
        assert!(reports(
            "out[0] = ballot16(running && n == 0u);",
            "right after a lane-divergent branch"
        ));
        // After a return that some lanes took (and so also right after their branch).
        assert!(!check("if g_lane == 1u { return; }\nout[0] = ballot16(true);").is_empty());
        assert!(reports(
            "if g_lane == 1u { return; }\nn = 1u;\nout[0] = ballot16(true);",
            IN_DIVERGENT_FLOW
        ));
        // In a loop that lanes leave at different passes.
        let divergent_loop =
            "loop { if !running { break; } n += 1u; out[n] = ballot16(true); running = n < g_lane; }";
        assert!(reports(divergent_loop, IN_DIVERGENT_FLOW));
        // A local assigned under a lane's branch is divergent, and so is a branch on it.
        assert!(reports(
            "var k = 0u;\nif running { k = 1u; }\nif k == 1u { out[0] = ballot16(true); }",
            IN_DIVERGENT_FLOW
        ));
    }

    #[test]
    fn the_check_accepts_group_uniform_control_flow() {
        assert!(check("out[0] = ballot16(running & (n == 0u));").is_empty());
        let uniform_loop = "loop { if !group_any(running) { break; } if n >= 5u { break; } n += 1u; \
                            if group_may(running) { out[n] = ballot16(running); } running = n < g_lane; }";
        assert!(check(uniform_loop).is_empty(), "{:?}", check(uniform_loop));
    }
}
