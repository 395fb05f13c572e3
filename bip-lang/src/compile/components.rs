//! Component families: the limits on their sizes checked before any is built, then each
//! instance with its slots in the state and its initial values (`vars_init` may read
//! `self_index`).

use super::resolve::{one_of, Ty};
use super::{check_name, unique, Compiler, MAX_COUNT, MAX_SLOTS, MAX_TOTAL};
use crate::diag::ModelError;
use crate::source::ConstExpr;
use crate::syntax::{ComponentDef, SystemDef};
use bip_model::{Component, Family, Var};

impl Compiler {
    pub(super) fn components(&mut self, def: &SystemDef) {
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
}
