//! A run as a timeline: one lane per participant, its states as coloured segments along
//! the steps (each segment labelled when it is wide enough, with a tooltip always),
//! events as marks on the lane (a request, an end), ticks as vertical rules. Groups:
//! `lane`, `segment <kind>`, `event <kind>`, `tick`.

use crate::svg::{num, text_width, Anchor, Font, Paint, Svg};

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Segment {
    /// The first step it covers and the step after its last (steps count from 0).
    pub from: usize,
    pub to: usize,
    /// What the participant is doing (`pending`, `running`, `paused`, …): its colour.
    pub kind: String,
    pub label: String,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Event {
    /// The step it happens at (from 0).
    pub at: usize,
    /// `request`, `done`, `error`, `interrupted`, …: its colour and shape.
    pub kind: String,
    pub label: String,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lane {
    pub name: String,
    pub segments: Vec<Segment>,
    pub events: Vec<Event>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Timeline {
    pub title: String,
    /// How many positions the horizontal axis has: steps of the run, or time units.
    pub steps: usize,
    /// What a position is, for the axis' label: `steps`, `units of 500 µs`.
    pub axis: String,
    /// Events and ticks are instants between positions (time), not positions (steps):
    /// drawn on the boundary before their position rather than in its middle.
    pub instants: bool,
    pub lanes: Vec<Lane>,
    /// The steps that are ticks.
    pub ticks: Vec<usize>,
    /// Each kind of segment and event, with what it means, for the legend.
    pub legend: Vec<(String, String)>,
}

const FONT: f64 = 11.0;
const MARGIN: f64 = 16.0;
const LANE: f64 = 26.0;
const BAR: f64 = 14.0;
/// The width the steps get, whatever their number (a step is at most `STEP_MAX` wide).
const SPAN: f64 = 1100.0;
const STEP_MAX: f64 = 14.0;

/// The colour of a kind of segment or event.
pub fn colour(kind: &str) -> &'static str {
    match kind {
        "pending" => "#f2c14e",
        "running" => "#4e79a7",
        "paused" => "#a0c4e8",
        "stopping" => "#b07aa1",
        "request" => "#1d5e8c",
        "done" => "#2e8b57",
        "error" | "miss" => "#c0392b",
        "ready" => "#f2c14e",
        "release" => "#1d5e8c",
        "job" => "#76b7b2",
        "interrupted" => "#7b3294",
        _ => "#999999",
    }
}

/// The timeline as an SVG document.
pub fn to_svg(t: &Timeline) -> String {
    let names = t
        .lanes
        .iter()
        .map(|l| text_width(&l.name, FONT) * 1.1)
        .fold(60.0, f64::max);
    let left = MARGIN + names + 12.0;
    // a time unit may be wider than a step: a schedule is short in units
    let widest = if t.instants { 4.0 * STEP_MAX } else { STEP_MAX };
    let step = (SPAN / t.steps.max(1) as f64).min(widest);
    let x = |s: usize| left + step * s as f64;
    let mark = if t.instants { 0.0 } else { step / 2.0 };
    let top = MARGIN + 30.0;
    let bottom = top + LANE * t.lanes.len() as f64;
    let width = (x(t.steps) + MARGIN)
        .max(MARGIN + text_width(&t.title, 14.0) + MARGIN)
        .max(700.0);
    // the legend, in as many rows as the width needs
    let mut legend = Vec::new();
    let (mut at, mut row) = (MARGIN, 0);
    for (kind, meaning) in &t.legend {
        let text = format!("{kind}: {meaning}");
        let w = text_width(&text, FONT) + 30.0;
        if at + w > width - MARGIN && at > MARGIN {
            at = MARGIN;
            row += 1;
        }
        legend.push((kind, text, at, row));
        at += w;
    }
    let legend_y = bottom + 30.0;
    let height = legend_y + 18.0 * (row + 1) as f64 + 8.0;

    let mut svg = Svg::new();
    svg.text(MARGIN, MARGIN + 10.0, &t.title, Font::new(14.0).bold());
    for &k in &t.ticks {
        svg.open("tick", None);
        let at = x(k) + mark;
        svg.line(at, top - 4.0, at, bottom, Paint::stroke("#dddddd"));
        svg.close();
    }
    svg.text(
        x(t.steps),
        top - 8.0,
        &format!("{} {}", t.steps, t.axis),
        Font::new(FONT - 1.0).colour("#888888").anchor(Anchor::End),
    );
    for (k, lane) in t.lanes.iter().enumerate() {
        let y = top + LANE * k as f64;
        let mid = y + LANE / 2.0;
        svg.open("lane", Some(&lane.name));
        svg.text(
            left - 12.0,
            mid + 4.0,
            &lane.name,
            Font::new(FONT).bold().anchor(Anchor::End),
        );
        svg.line(left, mid, x(t.steps), mid, Paint::stroke("#eeeeee"));
        for s in &lane.segments {
            let (x0, x1) = (x(s.from), x(s.to.max(s.from + 1)));
            svg.open(
                &format!("segment {}", s.kind),
                Some(&match t.instants {
                    true => format!("{}: {}, from {} to {}", lane.name, s.label, s.from, s.to),
                    false => format!("{}: {} (steps {}–{})", lane.name, s.label, s.from + 1, s.to),
                }),
            );
            svg.rect(
                x0,
                mid - BAR / 2.0,
                (x1 - x0).max(1.0),
                BAR,
                2.0,
                Paint::filled(colour(&s.kind), "none"),
            );
            if text_width(&s.label, FONT - 2.0) + 4.0 < x1 - x0 {
                svg.text(
                    (x0 + x1) / 2.0,
                    mid + 3.5,
                    &s.label,
                    Font::new(FONT - 2.0)
                        .colour("#ffffff")
                        .anchor(Anchor::Middle),
                );
            }
            svg.close();
        }
        for e in &lane.events {
            let at = x(e.at) + mark;
            svg.open(
                &format!("event {}", e.kind),
                Some(&match t.instants {
                    true => format!("at {}: {}", e.at, e.label),
                    false => format!("step {}: {}", e.at + 1, e.label),
                }),
            );
            let c = colour(&e.kind);
            let d = if e.kind == "request" || e.kind == "release" {
                // an arrow down onto the lane
                format!(
                    "M{},{} L{},{} L{},{} z",
                    num(at - 4.0),
                    num(y + 1.0),
                    num(at + 4.0),
                    num(y + 1.0),
                    num(at),
                    num(mid - BAR / 2.0)
                )
            } else {
                // an arrow up off the lane
                format!(
                    "M{},{} L{},{} L{},{} z",
                    num(at - 4.0),
                    num(y + LANE - 1.0),
                    num(at + 4.0),
                    num(y + LANE - 1.0),
                    num(at),
                    num(mid + BAR / 2.0)
                )
            };
            svg.path(&d, Paint::filled(c, "none"), None);
            svg.close();
        }
        svg.close();
    }
    for (kind, text, at, row) in legend {
        let y = legend_y + 18.0 * row as f64;
        svg.rect(
            at,
            y - 9.0,
            12.0,
            10.0,
            2.0,
            Paint::filled(colour(kind), "none"),
        );
        svg.text(at + 16.0, y, &text, Font::new(FONT).colour("#444444"));
    }
    svg.finish(width, height, &t.title)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_segments_events_and_ticks_are_groups() {
        let t = Timeline {
            title: "run".into(),
            steps: 10,
            axis: "steps".into(),
            instants: false,
            lanes: vec![Lane {
                name: "m.S".into(),
                segments: vec![
                    Segment {
                        from: 1,
                        to: 3,
                        kind: "pending".into(),
                        label: "pending".into(),
                    },
                    Segment {
                        from: 3,
                        to: 6,
                        kind: "running".into(),
                        label: "main".into(),
                    },
                ],
                events: vec![
                    Event {
                        at: 1,
                        kind: "request".into(),
                        label: "request".into(),
                    },
                    Event {
                        at: 5,
                        kind: "done".into(),
                        label: "ends".into(),
                    },
                ],
            }],
            ticks: vec![2, 7],
            legend: vec![("running".into(), "runs a codel".into())],
        };
        let doc = to_svg(&t);
        let classes = crate::xml::read::classes(&doc);
        let count = |prefix: &str| classes.iter().filter(|c| c.starts_with(prefix)).count();
        assert_eq!(count("lane"), 1);
        assert_eq!(count("segment"), 2);
        assert_eq!(count("event request"), 1);
        assert_eq!(count("event done"), 1);
        assert_eq!(count("tick"), 2);
        assert!(doc.contains("m.S: main (steps 4–6)"), "{doc}");
    }
}
