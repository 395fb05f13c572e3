//! The schedule run one microsecond at a time, the way it is defined: at every instant
//! the most urgent pending job of each CPU runs; jobs are released at every multiple of
//! their period below the horizon. No events, no merging: slow and plainly right.

use bip_sched::{Assignment, Micros, TaskSet};

/// Per task, its jobs' finish times (release `k · period` for job `k`).
pub fn finish_times(set: &TaskSet, assignment: Assignment, horizon: Micros) -> Vec<Vec<Micros>> {
    let mut finish = vec![Vec::new(); set.tasks.len()];
    for cpu in 0..set.cpus.len() {
        let order = set.by_priority(cpu, assignment);
        // per rank: (job index, work left), oldest first
        let mut pending: Vec<Vec<(usize, Micros)>> = vec![Vec::new(); order.len()];
        let mut released = vec![0usize; order.len()];
        let mut now = 0;
        loop {
            for (rank, &task) in order.iter().enumerate() {
                let t = &set.tasks[task];
                if now < horizon && now % t.period == 0 {
                    pending[rank].push((released[rank], t.demand));
                    finish[task].push(Micros::MAX);
                    released[rank] += 1;
                }
                // a job of no work is done at its release
                while let Some(&(job, 0)) = pending[rank].first() {
                    finish[task][job] = now;
                    pending[rank].remove(0);
                }
            }
            let busy = pending.iter().position(|q| !q.is_empty());
            if busy.is_none() && now >= horizon {
                break;
            }
            if let Some(rank) = busy {
                pending[rank][0].1 -= 1;
                if pending[rank][0].1 == 0 {
                    let (job, _) = pending[rank].remove(0);
                    finish[order[rank]][job] = now + 1;
                }
            }
            now += 1;
        }
    }
    finish
}
