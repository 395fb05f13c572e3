//! Validation and compilation of a [`SystemDef`] into a [`System`]: constants, atoms,
//! component families, `forall` connectors, priorities and properties, with every name
//! resolved and every expression type-checked. All errors are collected with positions.

mod choices;
mod priority;
mod resolve;

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};

use crate::diag::{Errors, ModelError};
use crate::expr::{self, ExprKind};
use crate::source::{ConstExpr, ConstValue, Span};
use crate::syntax::{
    parse_in_file, parse_range_in_file, ActionDef, AtomDef, ComponentDef, ConnectorDef,
    ConnectorKindDef, ExprDef, PropertyDef, SystemDef, Text, TypeDef,
};
use bip_model::eval;
use bip_model::{
    Assign, Atom, Component, Connector, Family, Interaction, PortRef, Priority, Property,
    PropertyKind, System, SystemParts, Target, Transition, Var, VarType,
};

pub(crate) use resolve::one_of;
pub use resolve::Ty;
use resolve::{ConstInfo, Names, Place, ResolveError, Resolver};

/// The largest family a model may declare; far beyond what any exploration handles, small
/// enough that a typo (`count: "10000000000"`) is an error rather than an out-of-memory.
const MAX_COUNT: i64 = 10_000_000;

/// The most components (and the most connector instances) a model may declare in all, over
/// every family (and every `forall`): the per-family limit alone lets a few families
/// together exhaust memory.
const MAX_TOTAL: usize = 10_000_000;

/// The most state slots (a location per component, and its variables) a model may have:
/// the state's tables take about 24 bytes a slot before any state is explored.
const MAX_SLOTS: usize = 50_000_000;

/// Compiles a core model (its GenoM layer, if any, is ignored: it must have been expanded
/// first), plus `extra` global boolean expressions over it (the GenoM layer's conditions,
/// for the engine's map). On failure, returns every error found.
pub(crate) fn compile_core(
    def: &SystemDef,
    extra: &[expr::Expr],
) -> Result<(System, Vec<eval::Expr>), Vec<ModelError>> {
    let mut c = Compiler::default();
    c.constants(def);
    c.atoms(def);
    c.components(def);
    c.connectors(def);
    for e in choices::check(def, &c.atoms, &c.components, &c.connectors, &c.interactions) {
        c.errors.push(e);
    }
    let priorities = c.priorities(def);
    let properties = c.properties(def);
    let extra: Vec<eval::Expr> = extra.iter().filter_map(|e| c.global_bool_tree(e)).collect();
    if !c.errors.is_empty() {
        return Err(c.errors.list);
    }
    let tick_ms = def.tick_ms.as_ref().and_then(|t| match t.value {
        ConstValue::Int(v) if v > 0 => Some(v as u64),
        _ => None,
    });
    if let Some(t) = &def.tick_ms {
        if tick_ms.is_none() {
            return Err(vec![ModelError::new(
                "`tick_ms` must be a positive integer",
                t.span,
            )]);
        }
    }
    let system = System::new(SystemParts {
        name: def.name.value.clone(),
        tick_ms,
        constants: c.const_list,
        atoms: c.atoms,
        families: c.families,
        components: c.components,
        connectors: c.connectors,
        interactions: c.interactions,
        priorities,
        properties,
        initial: c.initial,
        slot_ranges: c.slot_ranges,
        genom: None,
    });
    Ok((system, extra))
}

/// A model's constants, evaluated by the compiler's rules, for the GenoM expansion (task
/// periods, ages and limits written as constant expressions).
pub(crate) struct Constants {
    c: Compiler,
}

impl Constants {
    /// Evaluates the constants of `def`; errors in them are returned (and would be
    /// reported again by the compilation of the expanded model).
    pub(crate) fn new(def: &SystemDef) -> (Constants, Vec<ModelError>) {
        let mut c = Compiler::default();
        c.constants(def);
        let errors = std::mem::take(&mut c.errors.list);
        (Constants { c }, errors)
    }

    /// An integer written as a number or a constant expression.
    pub(crate) fn int(&self, v: &ConstExpr) -> Result<i64, ModelError> {
        self.c.const_value(v, Ty::Int, &[])
    }

    /// The value of a parsed expression if it is an integer constant expression.
    pub(crate) fn int_expr(&self, e: &expr::Expr) -> Option<i64> {
        let names = self.c.names();
        Resolver::new(&names, Place::Constant, &[])
            .constant(e, Ty::Int)
            .ok()
    }
}

#[derive(Default)]
struct Compiler {
    errors: Errors,
    consts: HashMap<String, ConstInfo>,
    const_list: Vec<(String, i64)>,
    atoms: Vec<Atom>,
    atom_by_name: HashMap<String, u32>,
    families: Vec<Family>,
    family_by_name: HashMap<String, u32>,
    components: Vec<Component>,
    slot_ranges: Vec<(i64, i64)>,
    initial: Vec<i64>,
    connectors: Vec<Connector>,
    connector_by_name: HashMap<String, u32>,
    /// Connectors that failed to compile: a priority naming one says nothing more.
    failed_connectors: HashSet<String>,
    interactions: Vec<Interaction>,
}

/// Turns an expression error into a model error (trees have their positions in the file).
fn expr_error(e: ResolveError) -> ModelError {
    let mut m = ModelError::new(e.message, e.span);
    m.help = e.help;
    m
}

/// Checks that a user-given name can be written in expressions.
pub(crate) fn check_name(errors: &mut Errors, name: &Text, what: &str) -> bool {
    let n = name.as_str();
    let ok = n
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        errors.push(
            ModelError::new(format!("`{n}` is not a valid {what} name"), name.span)
                .with_help("names use letters, digits and `_`, and do not start with a digit"),
        );
        return false;
    }
    if matches!(
        n,
        "true" | "false" | "forall" | "exists" | "sum" | "count" | "in" | "self_index"
    ) {
        errors.push(ModelError::new(
            format!("`{n}` is a reserved word and cannot name a {what}"),
            name.span,
        ));
        return false;
    }
    true
}

/// Reports duplicates among `names`; returns a map from name to first position.
pub(crate) fn unique<'t>(
    errors: &mut Errors,
    names: impl Iterator<Item = &'t Text>,
    what: &str,
) -> HashMap<&'t str, usize> {
    let mut seen: HashMap<&str, (usize, Span)> = HashMap::new();
    for (i, n) in names.enumerate() {
        if let Some(&(_, first)) = seen.get(n.as_str()) {
            errors.push(
                ModelError::new(format!("duplicate {what} `{n}`"), n.span)
                    .with_label("defined again here")
                    .with_note(first, "first defined here"),
            );
        } else {
            seen.insert(n.as_str(), (i, n.span));
        }
    }
    seen.into_iter().map(|(k, (i, _))| (k, i)).collect()
}

impl Compiler {
    fn names(&self) -> Names<'_> {
        Names {
            consts: &self.consts,
            atoms: &self.atoms,
            families: &self.families,
            family_by_name: &self.family_by_name,
            components: &self.components,
        }
    }

    /// Evaluates a constant written as a number, a boolean or an expression string.
    fn const_value(
        &self,
        v: &ConstExpr,
        want: Ty,
        fixed: &[(&str, i64)],
    ) -> Result<i64, ModelError> {
        let (value, ty) = self.const_any(v, fixed)?;
        if ty != want {
            return Err(ModelError::new(
                format!("expected {}, found {}", want.article(), ty.article()),
                v.span,
            ));
        }
        Ok(value)
    }

    /// Evaluates a constant of either type.
    fn const_any(&self, v: &ConstExpr, fixed: &[(&str, i64)]) -> Result<(i64, Ty), ModelError> {
        match &v.value {
            ConstValue::Int(i) => Ok((*i, Ty::Int)),
            ConstValue::Bool(b) => Ok((*b as i64, Ty::Bool)),
            ConstValue::Expr(_) => {
                let e = parse_in_file(&v.as_text())?;
                let names = self.names();
                let mut r = Resolver::new(&names, Place::Constant, fixed);
                r.constant_any(&e).map_err(expr_error)
            }
        }
    }

    fn constants(&mut self, def: &SystemDef) {
        unique(
            &mut self.errors,
            def.constants.iter().map(|(k, _)| k),
            "constant",
        );
        for (name, value) in def.constants.iter() {
            if !check_name(&mut self.errors, name, "constant")
                || self.consts.contains_key(name.as_str())
            {
                continue;
            }
            match self.const_any(value, &[]) {
                Ok((v, ty)) => {
                    self.consts
                        .insert(name.value.clone(), ConstInfo { value: v, ty });
                    self.const_list.push((name.value.clone(), v));
                }
                Err(e) => self.errors.push(e),
            }
        }
    }

    fn atoms(&mut self, def: &SystemDef) {
        unique(&mut self.errors, def.atoms.iter().map(|(k, _)| k), "atom");
        for (name, a) in def.atoms.iter() {
            if !check_name(&mut self.errors, name, "atom")
                || self.atom_by_name.contains_key(name.as_str())
            {
                continue;
            }
            let atom = self.atom(name, a);
            self.atom_by_name
                .insert(name.value.clone(), self.atoms.len() as u32);
            self.atoms.push(atom);
        }
    }

    fn atom(&mut self, name: &Text, a: &AtomDef) -> Atom {
        let errors = &mut self.errors;
        if a.locations.is_empty() {
            errors.push(ModelError::new(
                format!("atom `{name}` has no locations"),
                name.span,
            ));
        }
        for l in &a.locations {
            check_name(errors, l, "location");
        }
        for p in &a.ports {
            check_name(errors, p, "port");
        }
        let locs = unique(errors, a.locations.iter(), "location");
        let ports = unique(errors, a.ports.iter(), "port");
        unique(errors, a.vars.iter().map(|v| &v.name), "variable");
        let lookup_loc = |errors: &mut Errors, l: &Text| -> Option<u32> {
            let found = locs.get(l.as_str()).map(|&i| i as u32);
            if found.is_none() {
                errors.push(
                    ModelError::new(format!("atom `{name}` has no location `{l}`"), l.span)
                        .with_help(one_of(
                            "its locations are",
                            a.locations.iter().map(|l| l.as_str()),
                        )),
                );
            }
            found
        };
        let initial = lookup_loc(errors, &a.initial).unwrap_or(0);

        let mut vars = Vec::new();
        for v in &a.vars {
            check_name(&mut self.errors, &v.name, "variable");
            let ty = match &v.ty {
                TypeDef::Bool => VarType::Bool,
                TypeDef::Int(lo, hi) => {
                    let lo_v = self.const_value(lo, Ty::Int, &[]);
                    let hi_v = self.const_value(hi, Ty::Int, &[]);
                    match (lo_v, hi_v) {
                        (Ok(l), Ok(h)) if l <= h => VarType::Int { lo: l, hi: h },
                        (Ok(l), Ok(h)) => {
                            self.errors.push(ModelError::new(
                                format!("empty range: {l} is greater than {h}"),
                                lo.span,
                            ));
                            VarType::Int { lo: h, hi: h }
                        }
                        (l, h) => {
                            for e in [l.err(), h.err()].into_iter().flatten() {
                                self.errors.push(e);
                            }
                            VarType::Int { lo: 0, hi: 0 }
                        }
                    }
                }
            };
            let init = match &v.init {
                None => ty.range().0,
                Some(init) => self
                    .checked_init(init, &ty, &v.name, &[])
                    .unwrap_or(ty.range().0),
            };
            vars.push(Var {
                name: v.name.value.clone(),
                ty,
                init,
            });
        }

        // the atom as far as its transitions' guards and actions need it
        let atom = Atom::new(
            name.value.clone(),
            a.locations.iter().map(|l| l.value.clone()).collect(),
            initial,
            a.ports.iter().map(|p| p.value.clone()).collect(),
            vars,
            Vec::new(),
        );
        let mut transitions = Vec::new();
        for t in &a.transitions {
            let from = lookup_loc(&mut self.errors, &t.from);
            let to = lookup_loc(&mut self.errors, &t.to);
            let port = match &t.port {
                None => Some(None),
                Some(p) => match ports.get(p.as_str()) {
                    Some(&i) => Some(Some(i as u32)),
                    None => {
                        self.errors.push(
                            ModelError::new(format!("atom `{name}` has no port `{p}`"), p.span)
                                .with_help(one_of(
                                    "its ports are",
                                    a.ports.iter().map(|p| p.as_str()),
                                )),
                        );
                        None
                    }
                },
            };
            let guard = t.guard.as_ref().and_then(|g| self.atom_guard(&atom, g));
            let action = t
                .action
                .as_ref()
                .map(|act| self.atom_action(&atom, act))
                .unwrap_or_default();
            if let (Some(from), Some(to), Some(port)) = (from, to, port) {
                transitions.push(Transition {
                    from,
                    port,
                    to,
                    guard,
                    action,
                });
            }
        }
        Atom::new(
            atom.name,
            atom.locations,
            atom.initial,
            atom.ports,
            atom.vars,
            transitions,
        )
    }

    /// Checks an initial value against its variable's type and range.
    fn checked_init(
        &mut self,
        init: &ConstExpr,
        ty: &VarType,
        var: &str,
        fixed: &[(&str, i64)],
    ) -> Option<i64> {
        let want = match ty {
            VarType::Bool => Ty::Bool,
            VarType::Int { .. } => Ty::Int,
        };
        match self.const_value(init, want, fixed) {
            Ok(v) => {
                if let VarType::Int { lo, hi } = ty {
                    if v < *lo || v > *hi {
                        let mut e = ModelError::new(
                            format!(
                                "initial value {v} of `{var}` is outside its range Int({lo}, {hi})"
                            ),
                            init.span,
                        );
                        if let Some((_, k)) = fixed.iter().find(|(n, _)| *n == "self_index") {
                            e = e.with_help(format!("for the instance with self_index = {k}"));
                        }
                        self.errors.push(e);
                        return None;
                    }
                }
                Some(v)
            }
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    fn atom_guard(&mut self, atom: &Atom, g: &ExprDef) -> Option<eval::Expr> {
        let e = match g.tree() {
            Ok(e) => e,
            Err(e) => {
                self.errors.push(e);
                return None;
            }
        };
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Atom(atom), &[]);
        match r.expect(&e, Ty::Bool) {
            Ok(c) => Some(c),
            Err(e) => {
                self.errors.push(expr_error(e));
                None
            }
        }
    }

    fn atom_action(&mut self, atom: &Atom, act: &ActionDef) -> Vec<Assign> {
        let assigns = match act.tree() {
            Ok(a) => a,
            Err(e) => {
                self.errors.push(e);
                return Vec::new();
            }
        };
        let mut out = Vec::new();
        for a in assigns.iter() {
            let ExprKind::Name(n) = &a.target.kind else {
                self.errors.push(
                    ModelError::new(
                        "an atom's action assigns only its own variables",
                        a.target.span,
                    )
                    .with_help("write `x = …` with `x` a variable of this atom"),
                );
                continue;
            };
            let Some(v) = atom.var_index(n) else {
                self.errors.push(
                    ModelError::new(
                        format!("atom `{}` has no variable `{n}`", atom.name),
                        a.target.span,
                    )
                    .with_help(one_of(
                        "its variables are",
                        atom.vars.iter().map(|v| v.name.as_str()),
                    )),
                );
                continue;
            };
            let ty = match atom.vars[v as usize].ty {
                VarType::Bool => Ty::Bool,
                VarType::Int { .. } => Ty::Int,
            };
            let names = self.names();
            let mut r = Resolver::new(&names, Place::Atom(atom), &[]);
            match r.expect(&a.value, ty) {
                Ok(value) => out.push(Assign {
                    target: Target::Local(v),
                    value,
                }),
                Err(e) => self.errors.push(expr_error(e)),
            }
        }
        out
    }

    fn components(&mut self, def: &SystemDef) {
        unique(
            &mut self.errors,
            def.components.iter().map(|c| &c.name),
            "component",
        );
        // the total is checked before any family is built: building them is what exhausts
        // memory
        let (mut total, mut slots): (i64, i64) = (0, 0);
        for cd in &def.components {
            let n = match &cd.count {
                None => 1,
                Some(c) => match self.const_value(c, Ty::Int, &[]) {
                    Ok(n) if (1..=MAX_COUNT).contains(&n) => n,
                    _ => continue, // reported with its family
                },
            };
            total += n;
            if let Some(&a) = self.atom_by_name.get(cd.atom.as_str()) {
                slots += n * (1 + self.atoms[a as usize].vars.len() as i64);
            }
            if slots > MAX_SLOTS as i64 {
                self.errors.push(
                    ModelError::new(
                        format!(
                            "the families hold {slots} locations and variables up to here; at \
                             most {MAX_SLOTS} are allowed in all"
                        ),
                        cd.count.as_ref().map_or(cd.name.span, |c| c.span),
                    )
                    .with_help(
                        "each component holds its location and each of its atom's variables",
                    ),
                );
                return;
            }
            if total > MAX_TOTAL as i64 {
                self.errors.push(
                    ModelError::new(
                        format!(
                            "the families declare {total} components up to here; at most \
                             {MAX_TOTAL} are allowed in all"
                        ),
                        cd.count.as_ref().map_or(cd.name.span, |c| c.span),
                    )
                    .with_help("the limit is on the sum of the `count`s of all families"),
                );
                return;
            }
        }
        for cd in &def.components {
            if !check_name(&mut self.errors, &cd.name, "component")
                || self.family_by_name.contains_key(cd.name.as_str())
            {
                continue;
            }
            if self.consts.contains_key(cd.name.as_str()) {
                self.errors.push(ModelError::new(
                    format!("`{}` names both a constant and a component", cd.name),
                    cd.name.span,
                ));
                continue;
            }
            let Some(&atom) = self.atom_by_name.get(cd.atom.as_str()) else {
                self.errors.push(
                    ModelError::new(format!("unknown atom `{}`", cd.atom), cd.atom.span).with_help(
                        one_of("the atoms are", self.atoms.iter().map(|a| a.name.as_str())),
                    ),
                );
                continue;
            };
            self.family(cd, atom);
        }
    }

    fn family(&mut self, cd: &ComponentDef, atom: u32) {
        let count = match &cd.count {
            None => None,
            Some(c) => match self.const_value(c, Ty::Int, &[]) {
                Ok(n) if (1..=MAX_COUNT).contains(&n) => Some(n as u32),
                Ok(n) => {
                    self.errors.push(ModelError::new(
                        format!("`count` is {n}; it must be between 1 and {MAX_COUNT}"),
                        c.span,
                    ));
                    return;
                }
                Err(e) => {
                    self.errors.push(e);
                    return;
                }
            },
        };
        let a = &self.atoms[atom as usize];
        let mut overrides: Vec<(u32, &ConstExpr)> = Vec::new();
        unique(
            &mut self.errors,
            cd.vars_init.iter().map(|(k, _)| k),
            "initial value for",
        );
        for (var, value) in cd.vars_init.iter() {
            match a.var_index(var) {
                Some(v) => overrides.push((v, value)),
                None => self.errors.push(
                    ModelError::new(
                        format!("atom `{}` has no variable `{var}`", a.name),
                        var.span,
                    )
                    .with_help(one_of(
                        "its variables are",
                        a.vars.iter().map(|v| v.name.as_str()),
                    )),
                ),
            }
        }
        let fam = self.families.len() as u32;
        let first = self.components.len() as u32;
        let vars: Vec<Var> = a.vars.clone();
        let n_locs = a.locations.len() as i64;
        let initial_loc = i64::from(a.initial);
        let mut failed_override = vec![false; overrides.len()];
        for k in 0..count.unwrap_or(1) {
            let slot = self.slot_ranges.len() as u32;
            self.components.push(Component {
                name: match count {
                    Some(_) => format!("{}[{k}]", cd.name),
                    None => cd.name.value.clone(),
                },
                family: fam,
                atom,
                slot,
            });
            self.slot_ranges.push((0, (n_locs - 1).max(0)));
            self.initial.push(initial_loc);
            let fixed = [("self_index", i64::from(k))];
            for v in &vars {
                self.slot_ranges.push(v.ty.range());
                self.initial.push(v.init);
            }
            for (o, &(v, value)) in overrides.iter().enumerate() {
                if failed_override[o] {
                    continue; // report a bad `vars_init` once, not once per instance
                }
                match self.checked_init(value, &vars[v as usize].ty, &vars[v as usize].name, &fixed)
                {
                    Some(x) => self.initial[(slot + 1 + v) as usize] = x,
                    None => failed_override[o] = true,
                }
            }
        }
        self.family_by_name.insert(cd.name.value.clone(), fam);
        self.families.push(Family {
            name: cd.name.value.clone(),
            atom,
            count,
            first,
        });
    }

    fn connectors(&mut self, def: &SystemDef) {
        unique(
            &mut self.errors,
            def.connectors.iter().map(|c| &c.name),
            "connector",
        );
        for cd in &def.connectors {
            if !check_name(&mut self.errors, &cd.name, "connector")
                || self.connector_by_name.contains_key(cd.name.as_str())
            {
                continue;
            }
            if let Err(e) = self.connector(cd) {
                self.errors.push(e);
                self.failed_connectors.insert(cd.name.value.clone());
            }
        }
    }

    fn connector(&mut self, cd: &ConnectorDef) -> Result<(), ModelError> {
        if cd.ports.is_empty() {
            return Err(ModelError::new(
                format!("connector `{}` has no ports", cd.name),
                cd.name.span,
            ));
        }
        let (var, values) = match &cd.forall {
            None => (None, None),
            Some(f) => {
                let r = parse_range_in_file(f)?;
                let names = self.names();
                let mut res = Resolver::new(&names, Place::Constant, &[]);
                let lo = res.constant(&r.lo, Ty::Int).map_err(forall_bound)?;
                let hi = res.constant(&r.hi, Ty::Int).map_err(forall_bound)?;
                let size = i128::from(hi) - i128::from(lo);
                if size > i128::from(MAX_COUNT) {
                    return Err(ModelError::new(
                        format!("`forall` over {size} values; at most {MAX_COUNT} are allowed"),
                        f.span,
                    ));
                }
                let total = self.interactions.len() as i128 + size.max(0);
                if total > MAX_TOTAL as i128 {
                    return Err(ModelError::new(
                        format!(
                            "this `forall` brings the model to {total} connector instances; at \
                             most {MAX_TOTAL} are allowed in all"
                        ),
                        f.span,
                    ));
                }
                (Some(r.var.name.clone()), Some(lo..hi))
            }
        };
        // parse once, resolve per instance
        let ports: Vec<(Span, Cow<expr::Expr>)> = cd
            .ports
            .iter()
            .map(|p| p.tree().map(|e| (p.span(), e)))
            .collect::<Result<_, _>>()?;
        let trigger = match &cd.kind {
            ConnectorKindDef::Rendezvous => None,
            ConnectorKindDef::Broadcast { trigger } => Some((trigger.span(), trigger.tree()?)),
        };
        let guard = cd.guard.as_ref().map(ExprDef::tree).transpose()?;
        let action = cd.action.as_ref().map(ActionDef::tree).transpose()?;

        let id = self.connectors.len() as u32;
        let start = self.interactions.len() as u32;
        let indices: Vec<i64> = values.clone().map(|r| r.collect()).unwrap_or_default();
        let instances: Vec<Option<i64>> = match &values {
            None => vec![None],
            Some(_) => indices.iter().map(|&i| Some(i)).collect(),
        };
        for value in instances {
            let fixed_storage;
            let fixed: &[(&str, i64)] = match (&var, value) {
                (Some(v), Some(i)) => {
                    fixed_storage = [(v.as_str(), i)];
                    &fixed_storage
                }
                _ => &[],
            };
            let name = match value {
                Some(i) => format!("{}[{i}]", cd.name),
                None => cd.name.value.clone(),
            };
            let inter = self.interaction(cd, id, name, fixed, &ports, &trigger, &guard, &action)?;
            self.interactions.push(inter);
        }
        self.connector_by_name.insert(cd.name.value.clone(), id);
        self.connectors.push(Connector {
            name: cd.name.value.clone(),
            interactions: start..self.interactions.len() as u32,
            broadcast: trigger.is_some(),
            role: cd.role,
            indices,
        });
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn interaction(
        &self,
        cd: &ConnectorDef,
        id: u32,
        name: String,
        fixed: &[(&str, i64)],
        ports: &[(Span, Cow<expr::Expr>)],
        trigger: &Option<(Span, Cow<expr::Expr>)>,
        guard: &Option<Cow<expr::Expr>>,
        action: &Option<Cow<[expr::Assign]>>,
    ) -> Result<Interaction, ModelError> {
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Global, fixed);
        let at = |fixed: &[(&str, i64)]| match fixed.first() {
            Some((v, i)) => format!(" (in instance {v} = {i})"),
            None => String::new(),
        };
        let mut port_ref = |e: &expr::Expr| -> Result<PortRef, ModelError> {
            let (comp, member) = r.static_member(e).map_err(|err| {
                let mut m = expr_error(err);
                m.message.push_str(&at(fixed));
                m
            })?;
            let atom = &self.atoms[self.components[comp as usize].atom as usize];
            match atom.port_index(&member.name) {
                Some(port) => Ok(PortRef {
                    component: comp,
                    port,
                }),
                None => Err(ModelError::new(
                    format!("atom `{}` has no port `{}`", atom.name, member.name),
                    member.span,
                )
                .with_help(one_of(
                    "its ports are",
                    atom.ports.iter().map(String::as_str),
                ))),
            }
        };
        let mut refs = Vec::with_capacity(ports.len() + 1);
        let mut spans = Vec::with_capacity(ports.len() + 1);
        for (span, e) in ports {
            refs.push(port_ref(e)?);
            spans.push(*span);
        }
        let mut trigger_pos = None;
        if let Some((span, e)) = trigger {
            let t = port_ref(e)?;
            match refs.iter().position(|p| *p == t) {
                Some(k) => trigger_pos = Some(k as u32),
                None => {
                    refs.insert(0, t);
                    spans.insert(0, *span);
                    trigger_pos = Some(0);
                }
            }
        }
        for (k, p) in refs.iter().enumerate() {
            if let Some(j) = refs[..k].iter().position(|q| q.component == p.component) {
                return Err(ModelError::new(
                    format!(
                        "component `{}` appears twice in connector `{}`{}",
                        self.components[p.component as usize].name,
                        cd.name,
                        at(fixed)
                    ),
                    spans[k],
                )
                .with_note(spans[j], "first here")
                .with_help("a component takes part at most once in a connector"));
            }
        }
        let mut r = Resolver::new(&names, Place::Global, fixed);
        let guard = match guard {
            None => None,
            Some(e) => Some(r.expect(e, Ty::Bool).map_err(|err| {
                let mut m = expr_error(err);
                m.message.push_str(&at(fixed));
                m
            })?),
        };
        let mut assigns = Vec::new();
        if let Some(list) = action {
            for a in list.iter() {
                let fail = |err: ResolveError| {
                    let mut m = expr_error(err);
                    m.message.push_str(&at(fixed));
                    m
                };
                let (comp, member) = r.static_member(&a.target).map_err(fail)?;
                if !refs.iter().any(|p| p.component == comp) {
                    return Err(ModelError::new(
                        format!(
                            "`{}` is not in connector `{}`; a connector's action assigns only \
                             its participants' variables{}",
                            self.components[comp as usize].name,
                            cd.name,
                            at(fixed)
                        ),
                        a.target.span,
                    ));
                }
                let c = &self.components[comp as usize];
                let atom = &self.atoms[c.atom as usize];
                let Some(v) = atom.var_index(&member.name) else {
                    return Err(ModelError::new(
                        format!("atom `{}` has no variable `{}`", atom.name, member.name),
                        member.span,
                    ));
                };
                let ty = match atom.vars[v as usize].ty {
                    VarType::Bool => Ty::Bool,
                    VarType::Int { .. } => Ty::Int,
                };
                let value = r.expect(&a.value, ty).map_err(fail)?;
                assigns.push(Assign {
                    target: Target::Slot(c.var_slot(v)),
                    value,
                });
            }
        }
        Ok(Interaction {
            name,
            connector: id,
            ports: refs,
            trigger: trigger_pos,
            guard,
            action: assigns,
        })
    }

    fn priorities(&mut self, def: &SystemDef) -> Vec<Priority> {
        let mut declared = Vec::new();
        for p in &def.priorities {
            let low = self.priority_target(&p.low);
            let high = self.priority_target(&p.high);
            let when = match &p.when {
                None => Some(None),
                Some(w) => self.global_bool(w).map(Some),
            };
            if let (Some(low), Some(high), Some(when)) = (low, high, when) {
                declared.push(priority::Declared {
                    priority: Priority {
                        low,
                        high,
                        when,
                        text: format!("{} < {}", p.low, p.high),
                    },
                    span: p.low.span(),
                });
            }
        }
        match priority::check(declared) {
            Ok(r) => r,
            Err(e) => {
                self.errors.push(e);
                Vec::new()
            }
        }
    }

    /// `"left"` (every instance of a connector) or `"left[3]"` (the instance for the
    /// `forall` value 3) as a range of interactions.
    fn priority_target(&mut self, t: &ExprDef) -> Option<std::ops::Range<u32>> {
        let e = match t.tree() {
            Ok(e) => e,
            Err(e) => {
                self.errors.push(e);
                return None;
            }
        };
        let (name, index) = match &e.kind {
            ExprKind::Name(n) => (n, None),
            ExprKind::Index(base, idx) => match &base.kind {
                ExprKind::Name(n) => (n, Some(idx)),
                _ => (&String::new(), None),
            },
            _ => (&String::new(), None),
        };
        let Some(&c) = self.connector_by_name.get(name.as_str()) else {
            if self.failed_connectors.contains(name.as_str()) {
                return None;
            }
            let msg = if name.is_empty() {
                "expected a connector name or `connector[index]`".to_string()
            } else {
                format!("unknown connector `{name}`")
            };
            self.errors
                .push(ModelError::new(msg, t.span()).with_help(one_of(
                    "the connectors are",
                    self.connectors.iter().map(|c| c.name.as_str()),
                )));
            return None;
        };
        let conn = &self.connectors[c as usize];
        let Some(idx) = index else {
            return Some(conn.interactions.clone());
        };
        if conn.indices.is_empty() && conn.interactions.len() == 1 {
            self.errors.push(
                ModelError::new(
                    format!("connector `{name}` has no `forall`; it has no instances"),
                    t.span(),
                )
                .with_help(format!("write `{name}`")),
            );
            return None;
        }
        let names = self.names();
        let value = match Resolver::new(&names, Place::Constant, &[]).constant(idx, Ty::Int) {
            Ok(v) => v,
            Err(e) => {
                self.errors.push(expr_error(e));
                return None;
            }
        };
        match conn.indices.iter().position(|&v| v == value) {
            Some(k) => {
                let i = conn.interactions.start + k as u32;
                Some(i..i + 1)
            }
            None => {
                self.errors.push(ModelError::new(
                    format!("connector `{name}` has no instance {value}"),
                    idx.span,
                ));
                None
            }
        }
    }

    fn properties(&mut self, def: &SystemDef) -> Vec<Property> {
        let mut out = Vec::new();
        let mut seen: HashMap<String, Span> = HashMap::new();
        for p in &def.properties {
            let (name_span, text) = match p {
                PropertyDef::DeadlockFree { terminal } => (
                    terminal.as_ref().map_or(Span::NONE, ExprDef::span),
                    terminal.as_ref(),
                ),
                PropertyDef::Invariant { name, expr } | PropertyDef::Reachable { name, expr } => {
                    (name.span, Some(expr))
                }
            };
            let name = p.name().to_string();
            if let Some(&first) = seen.get(&name) {
                self.errors.push(
                    ModelError::new(format!("duplicate property `{name}`"), name_span)
                        .with_note(first, "first defined here"),
                );
                continue;
            }
            seen.insert(name.clone(), name_span);
            let compiled = match text {
                None => None,
                Some(t) => match self.global_bool(t) {
                    Some(e) => Some(e),
                    None => continue,
                },
            };
            let kind = match (p, compiled) {
                (PropertyDef::DeadlockFree { .. }, terminal) => {
                    PropertyKind::DeadlockFree { terminal }
                }
                (PropertyDef::Invariant { .. }, Some(e)) => PropertyKind::Invariant(e),
                (PropertyDef::Reachable { .. }, Some(e)) => PropertyKind::Reachable(e),
                _ => continue,
            };
            out.push(Property {
                name,
                kind,
                text: text.map(ExprDef::to_string).unwrap_or_default(),
            });
        }
        out
    }

    /// Parses and resolves a global boolean expression (property, priority condition).
    fn global_bool(&mut self, t: &ExprDef) -> Option<eval::Expr> {
        match t.tree() {
            Ok(e) => self.global_bool_tree(&e),
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    fn global_bool_tree(&mut self, e: &expr::Expr) -> Option<eval::Expr> {
        let names = self.names();
        let mut r = Resolver::new(&names, Place::Global, &[]);
        match r.expect(e, Ty::Bool) {
            Ok(c) => Some(c),
            Err(e) => {
                self.errors.push(expr_error(e));
                None
            }
        }
    }
}

fn forall_bound(mut e: ResolveError) -> ModelError {
    if e.message.starts_with("expected a constant") {
        e.message = "`forall` bounds must be constant expressions".into();
    }
    expr_error(e)
}
