//! `pendula serve`: the pendulum lab in the browser (crate `pendula-web`): prints the page's
//! URL, with its token, and serves until interrupted.

use std::net::IpAddr;

use anyhow::{Context, Result, bail};
use clap::Args;

#[derive(Debug, Clone, Args)]
pub struct ServeArgs {
    /// Port to listen on (0: any free port). Without it, 8485, a port no common tool uses
    /// (unassigned by IANA; not Jupyter's 8888, Dask's 8787 or any other usual default); when
    /// another program holds 8485, the first free one of 8486 to 8494 is taken, and said on
    /// stderr. A port given here is used or refused, never replaced.
    #[arg(long, value_name = "P")]
    pub port: Option<u16>,
    /// Address to listen on. Anything but a loopback address lets other machines reach the
    /// lab (each still needs the token): a warning is printed.
    #[arg(long, default_value = "127.0.0.1", value_name = "ADDR")]
    pub host: String,
    /// Open the page in the default browser (xdg-open; open on macOS).
    #[arg(long)]
    pub open: bool,
    /// Pages open at once; more are refused.
    #[arg(long, default_value_t = 32, value_name = "N")]
    pub max_sessions: usize,
}

/// The server's options from the flags, validated (nothing is bound or started: the fuzz
/// harness calls this alone, as the server never ends by itself).
pub fn options(args: &ServeArgs) -> Result<pendula_web::Options> {
    let host: IpAddr = args.host.parse().map_err(|_| {
        anyhow::anyhow!(
            "invalid value {:?} for --host: an IP address, e.g. 127.0.0.1 or ::1",
            crate::parse::clip(&args.host)
        )
    })?;
    if !(1..=10_000).contains(&args.max_sessions) {
        bail!("invalid value {} for --max-sessions: from 1 to 10000", args.max_sessions);
    }
    let limits = pendula_web::Limits { max_sessions: args.max_sessions, ..Default::default() };
    let port = args.port.unwrap_or(pendula_web::DEFAULT_PORT);
    Ok(pendula_web::Options { host, port, token: None, limits })
}

pub fn run(args: &ServeArgs) -> Result<()> {
    let options = options(args)?;
    let host = options.host;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the server's runtime")?;
    runtime.block_on(async {
        let refused = |e: std::io::Error| anyhow::Error::new(Refused(e.to_string()));
        let server = if args.port.is_some() {
            pendula_web::bind(options).await.map_err(refused)?
        } else {
            let (server, busy) = pendula_web::bind_default(options).await.map_err(refused)?;
            if let Some(first) = busy.first() {
                let ports = match busy.last() {
                    Some(last) if last != first => format!("ports {first} to {last} are"),
                    _ => format!("port {first} is"),
                };
                eprintln!(
                    "note: {ports} in use by another program; serving on port {} instead",
                    server.addr().port()
                );
            }
            server
        };
        if !host.is_loopback() {
            eprintln!(
                "warning: listening on {host}, reachable from other machines on that network (each page still needs the token)"
            );
        }
        let url = server.url();
        // A reader that went away (`pendula serve | head -1`) is no reason to stop serving.
        use std::io::Write;
        let mut out = std::io::stdout();
        let _ = writeln!(out, "pendula serve: the lab is at {url}");
        let _ = writeln!(out, "(Ctrl-C stops it; the token in the URL is what lets a page in)");
        let _ = out.flush();
        if args.open {
            open(&url);
        }
        server.run(std::future::pending()).await.context("the server stopped")
    })
}

/// The address could not be bound: the user's to fix (another port), exit code 2.
#[derive(Debug)]
struct Refused(String);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} (choose another with --port, or --port 0 for any free one)", self.0)
    }
}

impl std::error::Error for Refused {}

/// Asks the desktop to open `url`; a machine without one gets a note, not an error.
fn open(url: &str) {
    let opener = if cfg!(target_os = "macos") { "open" } else { "xdg-open" };
    if let Err(e) = std::process::Command::new(opener).arg(url).spawn() {
        eprintln!("note: could not open a browser ({opener}: {e}); open the URL above yourself");
    }
}
