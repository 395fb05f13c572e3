//! The GenoM layer's tasks as the scheduling analysis sees them: which interactions are
//! whose codel runs, and what each run costs.

use bip_model::{GenomMap, System};

/// One execution task of a module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayerTask {
    /// `module.task`.
    pub name: String,
    pub module: usize,
    /// Index into the module's tasks.
    pub task: usize,
    pub period_us: u64,
    pub cpu: u32,
    pub priority: Option<i64>,
    pub deadline_us: Option<u64>,
    /// Codels of its activities that declare no WCET, as `module.Service.codel`: they
    /// count as taking no time.
    pub unbudgeted: Vec<String>,
}

/// The tasks, and the cost of each interaction to each task.
#[derive(Clone, Debug)]
pub struct TaskTable {
    pub tasks: Vec<LayerTask>,
    /// Per interaction: `(task, WCET)` if it runs (or fails) a codel of a task's activity.
    pub cost: Vec<Option<(usize, u64)>>,
    /// The tick interaction: it ends every task's period.
    pub tick: u32,
}

impl TaskTable {
    /// The tasks of `system`'s GenoM layer, if it has one with a known tick length and at
    /// least one WCET.
    pub fn new(system: &System) -> Option<TaskTable> {
        let map: &GenomMap = system.genom.as_ref()?;
        let tick_us = map.tick_ms?.checked_mul(1000)?;
        let any_wcet = map
            .modules
            .iter()
            .flat_map(|m| &m.services)
            .flat_map(|s| &s.codels)
            .any(|c| c.wcet_us.is_some());
        if !any_wcet {
            return None;
        }
        let mut tasks = Vec::new();
        let mut cost = vec![None; system.interactions.len()];
        for (mi, module) in map.modules.iter().enumerate() {
            for (ti, task) in module.tasks.iter().enumerate() {
                let index = tasks.len();
                let mut unbudgeted = Vec::new();
                for service in module.services.iter().filter(|s| s.task == Some(ti)) {
                    for codel in &service.codels {
                        let wcet = match codel.wcet_us {
                            Some(w) => w,
                            None => {
                                unbudgeted.push(format!(
                                    "{}.{}.{}",
                                    module.name, service.name, codel.state
                                ));
                                0
                            }
                        };
                        for i in [codel.run, codel.fail] {
                            if let Some(slot) = cost.get_mut(i as usize) {
                                *slot = Some((index, wcet));
                            }
                        }
                    }
                }
                tasks.push(LayerTask {
                    name: format!("{}.{}", module.name, task.name),
                    module: mi,
                    task: ti,
                    period_us: u64::from(task.period).saturating_mul(tick_us),
                    cpu: task.cpu,
                    priority: task.priority,
                    deadline_us: task.deadline_us,
                    unbudgeted,
                });
            }
        }
        Some(TaskTable {
            tasks,
            cost,
            tick: map.tick,
        })
    }
}
