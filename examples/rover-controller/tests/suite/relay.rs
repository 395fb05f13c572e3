//! A TCP relay on loopback between a module process and the engine, which can be cut
//! off: while cut, it reads nothing from either side, as a pulled cable or a dead radio
//! link (the connections stay open, nothing passes); put back, what was sent flows again.
//! Its threads end when it is dropped.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

pub struct Relay {
    /// The port the module process connects to.
    pub port: u16,
    cut: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    streams: Arc<Mutex<Vec<TcpStream>>>,
    threads: Vec<JoinHandle<()>>,
}

impl Relay {
    /// Relays the connections made to a free port of 127.0.0.1 to `to_port`.
    pub fn start(to_port: u16) -> Relay {
        let listener = TcpListener::bind("127.0.0.1:0").expect("a free port");
        let port = listener.local_addr().expect("its address").port();
        listener.set_nonblocking(true).expect("non-blocking");
        let cut = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let streams = Arc::new(Mutex::new(Vec::new()));
        let accept = {
            let (cut, stop, streams) = (cut.clone(), stop.clone(), streams.clone());
            std::thread::spawn(move || {
                let mut pipes = Vec::new();
                while !stop.load(Ordering::Relaxed) {
                    let Ok((from, _)) = listener.accept() else {
                        std::thread::sleep(Duration::from_millis(10));
                        continue;
                    };
                    let Ok(to) = TcpStream::connect(("127.0.0.1", to_port)) else {
                        continue;
                    };
                    for s in [&from, &to] {
                        let _ = s.set_nonblocking(false);
                        let _ = s.set_read_timeout(Some(Duration::from_millis(20)));
                        let _ = s.set_nodelay(true);
                        if let Ok(c) = s.try_clone() {
                            streams.lock().expect("not poisoned").push(c);
                        }
                    }
                    let (Ok(from2), Ok(to2)) = (from.try_clone(), to.try_clone()) else {
                        continue;
                    };
                    pipes.push(pipe(from, to, cut.clone(), stop.clone()));
                    pipes.push(pipe(to2, from2, cut.clone(), stop.clone()));
                }
                for p in pipes {
                    let _ = p.join();
                }
            })
        };
        Relay {
            port,
            cut,
            stop,
            streams,
            threads: vec![accept],
        }
    }

    /// Cuts the link (`true`) or puts it back.
    pub fn set_cut(&self, cut: bool) {
        self.cut.store(cut, Ordering::Relaxed);
    }
}

/// Copies from `from` to `to` while not cut, until either side closes or the relay stops.
fn pipe(
    mut from: TcpStream,
    mut to: TcpStream,
    cut: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let mut buf = [0u8; 16 * 1024];
        while !stop.load(Ordering::Relaxed) {
            if cut.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
            match from.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    if to.write_all(&buf[..n]).is_err() {
                        break;
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => break,
            }
        }
        let _ = to.shutdown(Shutdown::Both);
        let _ = from.shutdown(Shutdown::Both);
    })
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for s in self.streams.lock().expect("not poisoned").iter() {
            let _ = s.shutdown(Shutdown::Both);
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}
