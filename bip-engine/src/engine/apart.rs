//! Async codels (docs/genom.md, "Async codels"; docs/engine.md, "Async codels"): the
//! model's start step launches the codel on a thread of its own, the task's thread goes
//! on, the return step is committed once the codel has returned, and its outcome step
//! takes what the run left. While it runs apart the codel works on copies, taken at the
//! start, of its module's ids and of the ports; its writes take effect at its outcome.

use std::sync::mpsc::{channel, sync_channel, Receiver, Sender, SyncSender};
use std::thread::JoinHandle;
use std::time::Duration;

#[allow(unused_imports)]
use crate::prelude::*;

use super::codels::CodelEnd;
use super::replies::Cause;
use super::{Engine, Stepped};
use crate::bind::Tables;
use crate::codel::{Body, CodelFn};
use crate::error::{EngineError, StepAsError};
use crate::event::Ticket;
use crate::threads::{run_job, Job};

/// The async codels' threads and runs.
#[derive(Default)]
pub(super) struct Apart {
    /// Per codel (empty if no codel is async): its run, from its start to its outcome.
    runs: Vec<Option<Run>>,
    threads: Vec<ApartThread>,
    /// The runs that returned, with their codel, from every thread.
    returns: Option<Receiver<(usize, Job)>>,
    /// Runs started whose return is not committed yet.
    pub(super) live: usize,
}

/// A run of an async codel.
pub(super) struct Run {
    /// When it started, and how long it took (once returned).
    pub t0: u64,
    pub took: Option<u64>,
    /// The request its activity served at the start.
    ticket: Option<Ticket>,
    /// A bound codel's job: on its thread (`None`) until it returns.
    pub job: Option<Job>,
    pub bound: bool,
    /// Its return step is committed.
    pub returned: bool,
}

struct ApartThread {
    to: SyncSender<Job>,
    thread: Option<JoinHandle<()>>,
}

impl Apart {
    /// Moves each bound async codel to a thread of its own (`Body::Apart`).
    pub fn spawn(t: &Tables, bodies: &mut [Body]) -> Apart {
        let mut apart = Apart::default();
        if t.codels.iter().all(|c| c.map.apart.is_none()) {
            return apart;
        }
        apart.runs = t.codels.iter().map(|_| None).collect();
        let (returned, returns) = channel::<(usize, Job)>();
        apart.returns = Some(returns);
        for (k, body) in bodies.iter_mut().enumerate() {
            if t.codels[k].map.apart.is_none() || !matches!(body, Body::Bound(_)) {
                continue;
            }
            let thread = apart.threads.len();
            let Body::Bound(f) = core::mem::replace(body, Body::Apart { thread }) else {
                continue;
            };
            let mut codels: Vec<(crate::codel::CodelInfo, CodelFn)> =
                vec![(t.codels[k].info.clone(), f)];
            let (to, jobs) = sync_channel::<Job>(1);
            let returned = returned.clone();
            let name = format!(
                "{}.{}.{}",
                t.codels[k].info.module, t.codels[k].info.service, t.codels[k].info.state
            );
            let thread = std::thread::Builder::new()
                .name(name)
                .spawn(move || serve(k, &mut codels, jobs, returned))
                .ok();
            apart.threads.push(ApartThread { to, thread });
        }
        apart
    }

    pub fn take(&mut self, ck: usize) -> Option<Run> {
        self.runs.get_mut(ck)?.take()
    }
}

impl Engine {
    /// Takes async codel `c`'s outcome: judges what its run left and commits the step
    /// it names, as [`Engine::run_codel`] for a synchronous codel.
    #[cold]
    #[inline(never)]
    pub(super) fn run_outcome(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        self.stage_ids(ck);
        let (end, t0, took) = self.apart_end(ck, forced);
        self.commit_codel(c, end, t0, took, forced, false)
    }

    /// The end of async codel `ck`'s run, at its outcome, with when it started and how
    /// long it took: what a bound codel left, its writes committed (the ids staged for
    /// the step, the ports it writes, its output); a default codel's outcome. Out of
    /// line: the synchronous codels' path does not carry it.
    #[cold]
    #[inline(never)]
    fn apart_end(&mut self, ck: usize, forced: bool) -> (CodelEnd, u64, u64) {
        let now = self.time.clock.now_us();
        let Some(mut run) = self.apart.take(ck) else {
            // an outcome with no run: a replayed trace that starts after the start
            return (self.default_end(ck, forced), now, 0);
        };
        let took = run.took.unwrap_or(0);
        let end = match run.job.take() {
            Some(mut job) => {
                self.runner.ids = core::mem::take(&mut job.ids);
                self.runner.written = job.written;
                self.runner.fault = job.fault.take();
                for &(k, _) in &self.t.codels[ck].info.ports {
                    self.runner.ports.take_from(&mut job.ports, k);
                }
                let service = self.t.codels[ck].service as usize;
                if let (Some(o), Some(a)) = (
                    job.output.take(),
                    self.t.services[service].activity.as_mut(),
                ) {
                    a.output = Some(o);
                }
                let result = job.result.take().unwrap_or_else(|| Err("no result".into()));
                self.classify(ck, result)
            }
            None if run.bound => self.classify(ck, Err("the codel's thread is gone".into())),
            None => self.default_end(ck, forced),
        };
        (end, run.t0, took)
    }
}

/// An async codel's thread: runs each job sent, and sends it back with its codel.
fn serve(
    codel: usize,
    codels: &mut [(crate::codel::CodelInfo, CodelFn)],
    jobs: Receiver<Job>,
    returned: Sender<(usize, Job)>,
) {
    while let Ok(mut job) = jobs.recv() {
        run_job(codels, &mut job);
        if returned.send((codel, job)).is_err() {
            return;
        }
    }
}

impl Drop for Apart {
    fn drop(&mut self) {
        for w in &mut self.threads {
            // closing the job channel ends the thread's loop once its codel returns
            let (dead, _) = sync_channel(0);
            drop(core::mem::replace(&mut w.to, dead));
            // a codel still running is not waited for (it may never return): its thread
            // is left detached, and ends when the codel returns, its result dropped
            if let Some(t) = w.thread.take() {
                if t.is_finished() {
                    let _ = t.join();
                }
            }
        }
    }
}

impl Engine {
    /// Commits the start of async codel `c` (the step chosen, or forced), then launches
    /// it apart: a bound codel on its thread, with copies of the ids and ports; a default
    /// codel returns at once.
    pub(super) fn start_apart(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        if !forced {
            let Some(a) = self.t.codels[ck].map.apart else {
                return Err(StepAsError::Engine(EngineError::Stopped(
                    self.internal_error(),
                )));
            };
            self.take_step_of(a.start);
        }
        self.commit(Cause::Other)?;
        let t0 = self.time.clock.now_us();
        let service = self.t.codels[ck].service as usize;
        let activity = self.t.services[service].activity.as_mut();
        let ticket = activity.as_ref().and_then(|a| a.current);
        let mut run = Run {
            t0,
            took: Some(0),
            ticket,
            job: None,
            bound: false,
            returned: false,
        };
        if let Body::Apart { thread } = self.runner.bodies[ck] {
            let ids = self.t.codels[ck]
                .info
                .fields
                .iter()
                .map(|f| self.gate.state().slots()[f.slot as usize])
                .collect();
            // the request's arguments go with it, and come back at its return
            let args = activity.and_then(|a| a.current_args.take());
            let job = Job {
                local: 0,
                ids,
                written: 0,
                fault: None,
                ports: self.runner.ports.copy(),
                args,
                output: None,
                now_us: t0,
                tick: self.stats.ticks,
                result: None,
            };
            run.took = None;
            run.bound = true;
            let sent = self
                .apart
                .threads
                .get(thread)
                .map(|w| w.to.send(job).is_ok());
            if sent != Some(true) {
                run.took = Some(0);
                run.job = None;
            }
        }
        if let Some(r) = self.apart.runs.get_mut(ck) {
            *r = Some(run);
            self.apart.live += 1;
        }
        Ok(Stepped::Other)
    }

    /// Commits the return of an async codel that has returned, if the model allows it
    /// now; false if there is none to commit.
    #[inline(never)]
    pub(super) fn return_apart(&mut self) -> Result<bool, EngineError> {
        for ck in 0..self.apart.runs.len() {
            let Some(a) = self.t.codels[ck].map.apart else {
                continue;
            };
            if !self.poll_run(ck, false) || !self.gate.enabled().is_enabled(a.returned) {
                continue;
            }
            self.take_step_of(a.returned);
            self.finish_return(ck)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Whether the run of codel `ck` has returned (and its return is not committed);
    /// with `wait`, waits for it (a thread gone ends the run: a fault at its outcome).
    fn poll_run(&mut self, ck: usize, wait: bool) -> bool {
        loop {
            match self.apart.runs.get(ck) {
                Some(Some(run)) if !run.returned => {
                    if run.took.is_some() {
                        return true;
                    }
                }
                _ => return false,
            }
            let got = if wait {
                self.receive_return(None)
            } else {
                self.receive_return(Some(Duration::ZERO))
            };
            if !got {
                if wait {
                    let now = self.time.clock.now_us();
                    if let Some(Some(run)) = self.apart.runs.get_mut(ck) {
                        run.took = Some(now.saturating_sub(run.t0));
                    }
                    return true;
                }
                return false;
            }
        }
    }

    /// Takes in a run that returned, waiting at most `timeout` (`None`: until one does);
    /// false if none did.
    fn receive_return(&mut self, timeout: Option<Duration>) -> bool {
        let Some(returns) = &self.apart.returns else {
            return false;
        };
        let got = match timeout {
            None => returns.recv().ok(),
            Some(Duration::ZERO) => returns.try_recv().ok(),
            Some(t) => returns.recv_timeout(t).ok(),
        };
        let Some((ck, job)) = got else {
            return false;
        };
        let now = self.time.clock.now_us();
        if let Some(Some(run)) = self.apart.runs.get_mut(ck) {
            run.took = Some(now.saturating_sub(run.t0));
            run.job = Some(job);
        }
        true
    }

    /// Waits for a run apart to return (nothing to wait for if none runs); true if one
    /// did. The engine waits so when it is idle, before time `t`: on a virtual clock for
    /// at most a tick's time, before it moves to the next tick (so that virtual time does
    /// not run ahead of a codel running apart), on a real clock until `t`.
    pub(super) fn wait_apart(&mut self, t: u64) -> bool {
        let wait_us = if self.time.clock.is_virtual() {
            self.time.tick_us
        } else {
            t.saturating_sub(self.time.clock.now_us())
        };
        wait_us > 0 && self.wait_for_return(Duration::from_micros(wait_us))
    }

    fn wait_for_return(&mut self, timeout: Duration) -> bool {
        let running = self
            .apart
            .runs
            .iter()
            .any(|r| r.as_ref().is_some_and(|r| r.took.is_none()));
        running && self.receive_return(Some(timeout))
    }

    /// Commits the return step chosen (or forced) for codel `ck`'s run.
    fn finish_return(&mut self, ck: usize) -> Result<(), EngineError> {
        self.commit(Cause::Other)?;
        self.apart.live = self.apart.live.saturating_sub(1);
        let service = self.t.codels[ck].service as usize;
        let Some(Some(run)) = self.apart.runs.get_mut(ck) else {
            return Ok(());
        };
        run.returned = true;
        // the arguments come back to the request they came from
        if let (Some(job), Some(a)) = (run.job.as_mut(), self.t.services[service].activity.as_mut())
        {
            if a.current == run.ticket && a.current.is_some() {
                a.current_args = job.args.take();
            }
        }
        Ok(())
    }

    /// A forced return step of codel `c` (replay): waits for a bound run to return.
    pub(super) fn force_return(&mut self, c: u32) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        self.poll_run(ck, true);
        self.finish_return(ck)?;
        Ok(Stepped::Other)
    }
}
