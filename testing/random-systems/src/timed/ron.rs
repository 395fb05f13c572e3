//! Writing a task set as a timed model file.

use super::{codel_name, Policy, Preemption, TaskSet, Yield};

/// A duration as the model file writes it.
fn duration(us: u64) -> String {
    if us.is_multiple_of(1000) {
        format!("{}ms", us / 1000)
    } else {
        format!("{us}us")
    }
}

impl TaskSet {
    /// The model file: CPUs `cpu0`, `cpu1`, …, modules `m0`, `m1`, … holding the tasks
    /// (named by [`super::Task::names`]), each task's machine of codels `start`, `c1`, ….
    pub fn to_ron(&self) -> String {
        let mut s = format!(
            "System(\n  name: \"timed\",\n  tick_ms: {},\n",
            self.tick_ms
        );
        match self.unit_us {
            Some(u) => s += &format!("  time: Exact(unit: \"{}\"),\n", duration(u)),
            None => s += "  time: Exact,\n",
        }
        s += "  cpus: [\n";
        for (i, c) in self.cpus.iter().enumerate() {
            let policy = match c.policy {
                Policy::FixedPriority => "FixedPriority",
                Policy::Edf => "Edf",
            };
            let preemption = match c.preemption {
                Preemption::Job => "Job",
                Preemption::Codel => "Codel",
                Preemption::Preemptive => "Preemptive",
            };
            s += &format!(
                "    (name: \"cpu{i}\", cores: {}, policy: {policy}, preemption: {preemption}),\n",
                c.cores
            );
        }
        s += "  ],\n  modules: [\n";
        let mut modules: Vec<usize> = self.tasks.iter().map(|t| t.module).collect();
        modules.dedup();
        // the ports `uses` names, declared only when some codel names one
        let ports = self
            .tasks
            .iter()
            .flat_map(|t| &t.codels)
            .any(|c| c.uses.iter().any(|&u| u == "p" || u == "q"));
        for &m in &modules {
            s += &format!("    (name: \"m{m}\", ");
            if ports {
                s += "ports: [(name: \"p\")], ";
                if m != 0 {
                    s += "in_ports: [(name: \"q\")], ";
                }
            }
            s += "tasks: [\n";
            for (i, t) in self.tasks.iter().enumerate().filter(|(_, t)| t.module == m) {
                let (_, name) = t.names(i);
                s += &format!(
                    "      (name: \"{name}\", period: {}, delay: {}, cpu: \"cpu{}\"",
                    t.period_ticks, t.delay_ticks, t.cpu
                );
                if self.cpus[t.cpu].policy == Policy::FixedPriority {
                    s += &format!(", priority: {}", t.priority);
                }
                if let Some(k) = t.core {
                    s += &format!(", core: {k}");
                }
                if let Some(d) = t.deadline_us {
                    s += &format!(", deadline: \"{}\"", duration(d));
                }
                s += ",\n       codels: [\n";
                for (ci, c) in t.codels.iter().enumerate() {
                    let yields: Vec<String> = c
                        .yields
                        .iter()
                        .map(|y| match *y {
                            Yield::Next(n) => format!("\"{}\"", codel_name(n)),
                            Yield::Pause(n) => format!("\"pause::{}\"", codel_name(n)),
                        })
                        .collect();
                    s += &format!(
                        "         (state: \"{}\", yields: [{}]",
                        codel_name(ci),
                        yields.join(", ")
                    );
                    if let Some(b) = c.bcet_us {
                        s += &format!(", bcet: \"{}\"", duration(b));
                    }
                    if let Some(w) = c.wcet_us {
                        s += &format!(", wcet: \"{}\"", duration(w));
                    }
                    if !c.uses.is_empty() {
                        let uses: Vec<String> = c.uses.iter().map(|u| format!("\"{u}\"")).collect();
                        s += &format!(", uses: [{}]", uses.join(", "));
                    }
                    s += "),\n";
                }
                s += "       ]),\n";
            }
            s += "    ]),\n";
        }
        s += "  ],\n";
        if ports && modules.len() > 1 {
            s += "  connections: [\n";
            for &m in modules.iter().filter(|&&m| m != 0) {
                s += &format!("    (port: \"m{m}.q\", reads: \"m0.p\"),\n");
            }
            s += "  ],\n";
        }
        s += ")\n";
        s
    }
}
