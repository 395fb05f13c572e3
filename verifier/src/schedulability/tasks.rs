//! The model's tasks as the scheduling analysis sees them: the GenoM layer's execution
//! tasks (which interactions are whose codel runs, and what each run costs) and the
//! components that stand for periodic tasks (their work per period declared).

use bip_model::{GenomMap, System};

/// One task of the model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayerTask {
    /// `module.task`, or the component's name.
    pub name: String,
    pub kind: TaskKind,
    pub period_us: u64,
    pub cpu: u32,
    pub priority: Option<i64>,
    pub deadline_us: Option<u64>,
    /// Codels of its activities that declare no WCET, as `module.Service.codel`: they
    /// count as taking no time.
    pub unbudgeted: Vec<String>,
}

/// Where a task's demand per period comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskKind {
    /// An execution task of a GenoM module: its demand is found from the codels its
    /// activities run in a period.
    Genom {
        module: usize,
        /// Index into the module's tasks.
        task: usize,
    },
    /// A component whose atom stands for a periodic task: its demand is its declared
    /// WCET per period.
    Component { component: u32, wcet_us: u64 },
}

/// The tasks, and the cost of each interaction to each GenoM task.
#[derive(Clone, Debug)]
pub struct TaskTable {
    /// The GenoM layer's tasks first, in declaration order, then the components'.
    pub tasks: Vec<LayerTask>,
    /// Per interaction: `(task, WCET)` if it runs (or fails) a codel of a task's activity.
    pub cost: Vec<Option<(usize, u64)>>,
    /// The tick interaction, which ends every GenoM task's period; `None` without
    /// GenoM tasks to analyse.
    pub tick: Option<u32>,
    /// The GenoM layer's tasks without a period, left out of the analysis, each with
    /// whether some codel it runs declares a WCET (its work between two releases of the
    /// other tasks then has no bound: the set cannot be analysed).
    pub aperiodic: Vec<(String, bool)>,
}

impl TaskTable {
    /// The tasks of `system`, if it has some to analyse: the GenoM layer's when it has a
    /// known tick length and at least one WCET, and the components that stand for tasks.
    pub fn new(system: &System) -> Option<TaskTable> {
        let mut table = TaskTable {
            tasks: Vec::new(),
            cost: vec![None; system.interactions.len()],
            tick: None,
            aperiodic: Vec::new(),
        };
        if let Some(map) = system.genom.as_ref() {
            table.add_layer(map);
        }
        for t in &system.budgets.tasks {
            table.tasks.push(LayerTask {
                name: system.components[t.component as usize].name.clone(),
                kind: TaskKind::Component {
                    component: t.component,
                    wcet_us: t.wcet_us,
                },
                period_us: t.period_us,
                cpu: t.cpu,
                priority: t.priority,
                deadline_us: t.deadline_us,
                unbudgeted: Vec::new(),
            });
        }
        (!table.tasks.is_empty()).then_some(table)
    }

    /// True if some task's demand is found from the model's codels.
    pub fn has_codel_tasks(&self) -> bool {
        self.tick.is_some()
    }

    fn add_layer(&mut self, map: &GenomMap) {
        let Some(tick_us) = map.tick_ms.and_then(|ms| ms.checked_mul(1000)) else {
            return;
        };
        let any_wcet = map
            .modules
            .iter()
            .flat_map(|m| &m.services)
            .flat_map(|s| &s.codels)
            .any(|c| c.wcet_us.is_some());
        if !any_wcet {
            return;
        }
        self.tick = Some(map.tick);
        for (mi, module) in map.modules.iter().enumerate() {
            for (ti, task) in module.tasks.iter().enumerate() {
                let name = format!("{}.{}", module.name, task.name);
                // a task without a period has no work per period to analyse: without
                // WCETs it takes no time, as an unbudgeted codel does; with some, no
                // bound can be given (`TaskTable::aperiodic`)
                let Some(period) = task.period else {
                    let budgeted = module
                        .services
                        .iter()
                        .filter(|s| s.task == Some(ti))
                        .flat_map(|s| &s.codels)
                        .any(|c| c.wcet_us.is_some() && c.apart.is_none());
                    self.aperiodic.push((name, budgeted));
                    continue;
                };
                let index = self.tasks.len();
                let mut unbudgeted = Vec::new();
                for service in module.services.iter().filter(|s| s.task == Some(ti)) {
                    // an async codel runs apart from its task: not its demand
                    for codel in service.codels.iter().filter(|c| c.apart.is_none()) {
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
                            if let Some(slot) = self.cost.get_mut(i as usize) {
                                *slot = Some((index, wcet));
                            }
                        }
                    }
                }
                self.tasks.push(LayerTask {
                    name,
                    kind: TaskKind::Genom {
                        module: mi,
                        task: ti,
                    },
                    period_us: u64::from(period).saturating_mul(tick_us),
                    cpu: task.cpu,
                    priority: task.priority,
                    deadline_us: task.deadline_us,
                    unbudgeted,
                });
            }
        }
    }
}
