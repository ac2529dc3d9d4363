//! A device model on a pseudo-terminal, stepped by a thread of its own until dropped, for the
//! older end-to-end tests that hold the model behind a mutex (the newer ones use
//! `vrpn::sim::SimulatedDevice`).
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use vrpn::sim::{DeviceModel, PtyDevice};
use vrpn::Now;

/// Runs a device model on a pseudo-terminal in a thread until dropped.
pub struct Simulated<M: DeviceModel + Send + 'static> {
    device: Arc<Mutex<PtyDevice<M>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The pseudo-terminal's path (in a directory of its own, removed on drop).
    pub path: PathBuf,
}

impl<M: DeviceModel + Send + 'static> Simulated<M> {
    /// Opens `model` on a pseudo-terminal named after `name` and steps it every 200 µs.
    pub fn start(model: M, name: &str) -> Simulated<M> {
        let dir = std::env::temp_dir().join(format!("vrpn-pty-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tty");
        let device = Arc::new(Mutex::new(PtyDevice::open(model, &path).unwrap()));
        let stop = Arc::new(AtomicBool::new(false));
        let (d, s) = (device.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                let _ = d.lock().unwrap().step(Now::read());
                std::thread::sleep(Duration::from_micros(200));
            }
        });
        Simulated {
            device,
            stop,
            thread: Some(thread),
            path,
        }
    }

    /// The device, its thread paused meanwhile.
    pub fn lock(&self) -> MutexGuard<'_, PtyDevice<M>> {
        self.device.lock().unwrap()
    }

    /// Runs `f` on the model with the current time.
    pub fn with<R>(&self, f: impl FnOnce(&mut M, Now) -> R) -> R {
        f(&mut self.lock().model, Now::read())
    }

    /// Unplugs the simulated device (the server's port fails) or plugs it back.
    pub fn set_plugged(&self, plugged: bool) {
        let mut d = self.lock();
        if plugged {
            d.plug().unwrap();
        } else {
            d.unplug();
        }
    }
}

impl<M: DeviceModel + Send + 'static> Drop for Simulated<M> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(dir) = self.path.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}
