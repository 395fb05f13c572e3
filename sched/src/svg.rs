//! A schedule as a picture: one lane per task, grouped by CPU, most urgent first; its
//! runs as bars (a gap inside a job is a preemption), releases as arrows up, deadlines as
//! ticks down, a missed deadline in red; a time axis in milliseconds.

use std::fmt::Write;

use bip_picture::xml::escape;

use crate::simulate::Schedule;
use crate::task::{Assignment, Micros, TaskSet};

const LEFT: f64 = 150.0;
const WIDTH: f64 = 900.0;
const LANE: f64 = 34.0;
const TOP: f64 = 40.0;
const COLOURS: [&str; 8] = [
    "#4e79a7", "#f28e2b", "#59a14f", "#b07aa1", "#76b7b2", "#edc948", "#9c755f", "#bab0ac",
];

/// The picture of `schedule`, a run of `set`; `title` heads it.
pub fn schedule_svg(
    set: &TaskSet,
    assignment: Assignment,
    schedule: &Schedule,
    title: &str,
) -> String {
    let lanes: Vec<(usize, usize)> = (0..set.cpus.len())
        .flat_map(|cpu| {
            set.by_priority(cpu, assignment)
                .into_iter()
                .map(move |t| (cpu, t))
        })
        .collect();
    let span = schedule.end.max(schedule.horizon).max(1);
    let x = |t: Micros| LEFT + WIDTH * t as f64 / span as f64;
    let height = TOP + LANE * lanes.len() as f64 + 50.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{height}" viewBox="0 0 {w} {height}" font-family="sans-serif" font-size="12">"#,
        w = LEFT + WIDTH + 30.0
    );
    let _ = writeln!(s, r#"<title>{}</title>"#, escape(title));
    let _ = writeln!(
        s,
        r#"<text x="10" y="20" font-size="14" font-weight="bold">{}</text>"#,
        escape(title)
    );
    let mut previous_cpu = None;
    for (lane, &(cpu, task)) in lanes.iter().enumerate() {
        let top = TOP + LANE * lane as f64;
        let base = top + LANE - 8.0;
        if previous_cpu != Some(cpu) {
            let _ = writeln!(
                s,
                r##"<line x1="10" y1="{top}" x2="{}" y2="{top}" stroke="#999"/><text class="cpu" x="10" y="{}" fill="#666" font-size="10" font-weight="bold">CPU {}</text>"##,
                LEFT + WIDTH,
                top + 11.0,
                escape(&set.cpus[cpu])
            );
            previous_cpu = Some(cpu);
        }
        let t = &set.tasks[task];
        let _ = writeln!(
            s,
            r#"<text x="10" y="{base}" class="task">{}</text>"#,
            escape(&t.name)
        );
        let colour = COLOURS[task % COLOURS.len()];
        let trace = &schedule.tasks[task];
        for run in &trace.runs {
            let _ = writeln!(
                s,
                r#"<rect class="run" x="{:.2}" y="{}" width="{:.2}" height="16" fill="{colour}"><title>{} job {}: {}–{} µs</title></rect>"#,
                x(run.start),
                base - 16.0,
                (x(run.end) - x(run.start)).max(0.5),
                escape(&t.name),
                run.job,
                run.start,
                run.end
            );
        }
        for job in &trace.jobs {
            let rx = x(job.release);
            let _ = writeln!(
                s,
                r##"<path class="release" d="M{rx:.2} {base} V{} l-3 5 h6 l-3 -5" stroke="#333" fill="#333"/>"##,
                base - 24.0
            );
            let (stroke, class) = if job.missed() {
                ("#d62728", "miss")
            } else {
                ("#333", "deadline")
            };
            let dx = x(job.deadline.min(span));
            let _ = writeln!(
                s,
                r#"<path class="{class}" d="M{dx:.2} {} V{base} l-3 -5 m3 5 l3 -5" stroke="{stroke}" fill="none"/>"#,
                base - 22.0
            );
        }
    }
    let axis = TOP + LANE * lanes.len() as f64 + 10.0;
    let _ = writeln!(
        s,
        r##"<line x1="{LEFT}" y1="{axis}" x2="{}" y2="{axis}" stroke="#333"/>"##,
        LEFT + WIDTH
    );
    let step = tick_step(span);
    let mut tick = 0;
    while tick <= span {
        let tx = x(tick);
        let _ = writeln!(
            s,
            r##"<line x1="{tx:.2}" y1="{axis}" x2="{tx:.2}" y2="{}" stroke="#333"/><text x="{tx:.2}" y="{}" text-anchor="middle">{}</text>"##,
            axis + 5.0,
            axis + 18.0,
            millis(tick)
        );
        tick += step;
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">ms</text>"#,
        LEFT + WIDTH,
        axis + 34.0
    );
    s.push_str("</svg>\n");
    s
}

/// A round step giving at most about ten ticks.
fn tick_step(span: Micros) -> Micros {
    let mut step: Micros = 1;
    loop {
        for m in [1, 2, 5] {
            if span / (step * m) <= 10 {
                return step * m;
            }
        }
        step *= 10;
    }
}

fn millis(us: Micros) -> String {
    if us.is_multiple_of(1000) {
        format!("{}", us / 1000)
    } else {
        format!("{}", us as f64 / 1000.0)
    }
}
