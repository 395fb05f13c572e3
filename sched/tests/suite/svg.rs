//! The schedule's picture, read back as XML: every task has its lane, every run its bar,
//! every release its arrow, and a missed deadline is marked.

use bip_sched::{analyse, hyperperiod, schedule_svg, simulate, Assignment, Task, TaskSet};

#[test]
fn every_task_run_and_release_is_drawn_and_misses_are_marked() {
    let set = TaskSet {
        cpus: vec!["main".into()],
        tasks: [("nav", 4, 1), ("loc", 6, 2), ("map <&>", 10, 4)]
            .into_iter()
            .map(|(name, period, demand)| Task {
                name: name.into(),
                cpu: 0,
                period,
                demand,
                deadline: period,
                priority: None,
            })
            .collect(),
    };
    let horizon = hyperperiod(&set).unwrap();
    let schedule = simulate(&set, Assignment::Given, horizon, 1000).unwrap();
    assert!(!analyse(&set, Assignment::Given).unwrap().schedulable(&set));
    let svg = schedule_svg(&set, Assignment::Given, &schedule, "rover <nav>");
    let doc = roxmltree::Document::parse(&svg).expect("the SVG is XML");
    let class = |c: &str| {
        doc.descendants()
            .filter(|n| n.attribute("class") == Some(c))
            .count()
    };
    let runs: usize = schedule.tasks.iter().map(|t| t.runs.len()).sum();
    let jobs: usize = schedule.tasks.iter().map(|t| t.jobs.len()).sum();
    let missed: usize = schedule
        .tasks
        .iter()
        .flat_map(|t| &t.jobs)
        .filter(|j| j.missed())
        .count();
    assert!(missed > 0);
    assert_eq!(class("run"), runs);
    assert_eq!(class("release"), jobs);
    assert_eq!(class("miss"), missed);
    assert_eq!(class("deadline") + class("miss"), jobs);
    let names: Vec<&str> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("task"))
        .filter_map(|n| n.text())
        .collect();
    assert_eq!(names, ["nav", "loc", "map <&>"]);
}
