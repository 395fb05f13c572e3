//! Task threads: the codels of each task run on a thread of their own, one codel at a
//! time, dispatched and committed by the engine (docs/engine.md, "Threads").

use std::any::Any;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use crate::bind::Tables;
use crate::codel::{call_guarded, Body, CodelFn, CodelInfo, Ctx, CtxFault, ModuleFn, Next};
use crate::event::Output;
use crate::ports::PortStore;

/// A codel run sent to a task thread, and sent back with its result. Everything moves
/// (nothing is copied or allocated per run).
pub(crate) struct Job {
    pub local: usize,
    pub ids: Vec<i64>,
    pub written: u64,
    pub fault: Option<CtxFault>,
    pub ports: PortStore,
    pub args: Option<Box<dyn Any + Send>>,
    pub output: Option<Output>,
    pub now_us: u64,
    pub tick: u64,
    pub result: Option<Result<Next, String>>,
}

struct Worker {
    to: SyncSender<Job>,
    from: Receiver<Job>,
    thread: Option<JoinHandle<()>>,
}

pub(crate) struct Workers {
    workers: Vec<Worker>,
}

impl Workers {
    /// One thread per task that has bound codels; the bound codels move there.
    pub fn spawn(t: &Tables, bodies: &mut [Body]) -> Workers {
        // tasks by (module, task) name
        let mut tasks: Vec<(String, String)> = Vec::new();
        let mut per_task: Vec<Vec<(CodelInfo, CodelFn)>> = Vec::new();
        for (k, body) in bodies.iter_mut().enumerate() {
            if !matches!(body, Body::Bound(_)) {
                continue;
            }
            let c = &t.codels[k];
            let key = (c.info.module.clone(), task_of(t, k));
            let w = match tasks.iter().position(|x| *x == key) {
                Some(w) => w,
                None => {
                    tasks.push(key);
                    per_task.push(Vec::new());
                    tasks.len() - 1
                }
            };
            let Body::Bound(f) = core::mem::replace(
                body,
                Body::Thread {
                    worker: w,
                    local: per_task[w].len(),
                },
            ) else {
                continue;
            };
            per_task[w].push((c.info.clone(), f));
        }
        let workers = per_task
            .into_iter()
            .zip(tasks)
            .map(|(codels, (module, task))| {
                let (to, jobs) = sync_channel::<Job>(1);
                let (done, from) = sync_channel::<Job>(1);
                let thread = std::thread::Builder::new()
                    .name(format!("{module}.{task}"))
                    .spawn(move || serve(codels, jobs, done))
                    .ok();
                Worker { to, from, thread }
            })
            .collect();
        Workers { workers }
    }

    /// Runs a job on worker `w` and waits for it; `None` if the thread is gone.
    pub fn run(&mut self, w: usize, job: Job) -> Option<Job> {
        let worker = self.workers.get(w)?;
        worker.to.send(job).ok()?;
        worker.from.recv().ok()
    }
}

impl Drop for Workers {
    fn drop(&mut self) {
        for w in &mut self.workers {
            // closing the job channel ends the thread's loop
            let (dead, _) = sync_channel(0);
            drop(core::mem::replace(&mut w.to, dead));
            if let Some(t) = w.thread.take() {
                let _ = t.join();
            }
        }
    }
}

/// Task threads call codels bound one by one: each module object becomes one closure per
/// codel, sharing it behind a lock (its codels may run on several tasks' threads; the
/// lock is uncontended when they run on one, and costs little beside the threads'
/// hand-over).
pub(crate) fn share_modules(bodies: &mut [Body], modules: Vec<ModuleFn>) {
    let modules: Vec<Arc<Mutex<ModuleFn>>> = modules
        .into_iter()
        .map(|m| Arc::new(Mutex::new(m)))
        .collect();
    for body in bodies.iter_mut() {
        if let Body::Module { module, local } = *body {
            let Some(m) = modules.get(module).cloned() else {
                continue;
            };
            *body = Body::Bound(Box::new(move |ctx| {
                let mut f = m.lock().unwrap_or_else(PoisonError::into_inner);
                f(local, ctx)
            }));
        }
    }
}

fn task_of(t: &Tables, codel: usize) -> String {
    let s = &t.services[t.codels[codel].service as usize];
    s.task.clone().unwrap_or_else(|| s.name.clone())
}

fn serve(mut codels: Vec<(CodelInfo, CodelFn)>, jobs: Receiver<Job>, done: SyncSender<Job>) {
    while let Ok(mut job) = jobs.recv() {
        run_job(&mut codels, &mut job);
        if done.send(job).is_err() {
            return;
        }
    }
}

/// Calls the job's codel among `codels`, leaving its result in the job.
pub(crate) fn run_job(codels: &mut [(CodelInfo, CodelFn)], job: &mut Job) {
    let result = match codels.get_mut(job.local) {
        Some((info, f)) => {
            let mut ctx = Ctx {
                info,
                ids: &mut job.ids,
                written: &mut job.written,
                fault: core::cell::Cell::from_mut(&mut job.fault),
                ports: &mut job.ports,
                args: job.args.as_deref(),
                output: Some(&mut job.output),
                now_us: job.now_us,
                tick: job.tick,
            };
            call_guarded(&mut ctx, &mut **f)
        }
        None => Err("no such codel on this thread".into()),
    };
    job.result = Some(result);
}
