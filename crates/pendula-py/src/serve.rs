//! `pendula.view`: the browser lab (`pendula-web`, the server behind `pendula serve`) started
//! once per Python process on a free loopback port, on a thread of its own.

use std::sync::OnceLock;

use pyo3::prelude::*;

/// The running lab's URL (with its token), or why it could not start.
static LAB: OnceLock<Result<String, String>> = OnceLock::new();

/// Starts the lab on 127.0.0.1 (any free port) unless it runs already; returns its URL.
#[pyfunction]
fn serve(py: Python<'_>) -> PyResult<String> {
    let started = py.detach(|| {
        LAB.get_or_init(|| {
            let (tx, rx) = std::sync::mpsc::channel();
            let spawned = std::thread::Builder::new().name("pendula-lab".into()).spawn(move || {
                let runtime = match tokio::runtime::Builder::new_multi_thread()
                    .worker_threads(2)
                    .enable_all()
                    .build()
                {
                    Ok(r) => r,
                    Err(e) => return drop(tx.send(Err(format!("cannot start the lab's runtime: {e}")))),
                };
                runtime.block_on(async move {
                    let options = pendula_web::Options { port: 0, ..Default::default() };
                    match pendula_web::bind(options).await {
                        Ok(server) => {
                            let _ = tx.send(Ok(server.url()));
                            // Serves for the rest of the process.
                            let _ = server.run(std::future::pending()).await;
                        }
                        Err(e) => drop(tx.send(Err(e.to_string()))),
                    }
                });
            });
            match spawned {
                Ok(_) => rx.recv().unwrap_or_else(|_| Err("the lab's thread ended before it started".into())),
                Err(e) => Err(format!("cannot start the lab's thread: {e}")),
            }
        })
        .clone()
    });
    started.map_err(pyo3::exceptions::PyRuntimeError::new_err)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(serve, m)?)
}
