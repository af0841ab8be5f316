//! rvc-ros2dds-bridge: a Zenoh router with the `zenoh-plugin-ros2dds` plugin (crates.io) linked in
//! statically. It stands in for Eclipse's `zenoh-bridge-ros2dds` binary, which is not published on
//! crates.io, so rvc's tests can check what the real plugin forwards (docs/zenoh.md, "The real
//! zenoh-bridge-ros2dds").
//!
//! Usage: rvc-ros2dds-bridge CONFIG.json5
//!   CONFIG is an ordinary Zenoh configuration with a `plugins.ros2dds` object (the plugin's own
//!   options: domain, namespace, allow/deny ...).
//!
//! A test tool that must never reach past the machine, so before starting it checks that:
//!   - every listen/connect endpoint is a loopback TCP address or a unix socket,
//!   - multicast scouting is off,
//!   - CYCLONEDDS_URI is set (the plugin's CycloneDDS reads it; the caller pins it to `lo`).
//! It prints one line `ready <zid>` on stdout once the router and the plugin have started, and
//! stops on SIGINT/SIGTERM. Exit status: 0 stopped by a signal, 2 bad config, 1 failed to start.

use std::process::ExitCode;

use zenoh::internal::{plugins::PluginsManager, runtime::RuntimeBuilder};

const PLUGIN: &str = "ros2dds";

fn main() -> ExitCode {
    zenoh::init_log_from_env_or("warn");
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 2 || args[1].starts_with('-') {
        eprintln!("usage: rvc-ros2dds-bridge CONFIG.json5 (a Zenoh config with plugins.{PLUGIN})");
        return ExitCode::from(2);
    }
    let config = match zenoh::Config::from_file(&args[1]) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("rvc-ros2dds-bridge: {}: {e}", args[1]);
            return ExitCode::from(2);
        }
    };
    if let Err(problem) = check_stays_local(&config) {
        eprintln!("rvc-ros2dds-bridge: {}: {problem}", args[1]);
        return ExitCode::from(2);
    }
    let rt = match tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("rvc-ros2dds-bridge: cannot start the async runtime: {e}");
            return ExitCode::from(1);
        }
    };
    rt.block_on(run(config))
}

async fn run(config: zenoh::Config) -> ExitCode {
    // Only the one plugin, linked in: no plugin search path, nothing loaded from disk.
    let mut plugins = PluginsManager::static_plugins_only();
    plugins.declare_static_plugin::<zenoh_plugin_ros2dds::ROS2Plugin, &str>(PLUGIN, true);
    // build() also starts the declared plugins (a required one that fails panics there).
    let mut runtime = match RuntimeBuilder::new(config).plugins_manager(plugins).build().await {
        Ok(r) => r,
        Err(e) => {
            eprintln!("rvc-ros2dds-bridge: cannot build the Zenoh runtime: {e}");
            return ExitCode::from(1);
        }
    };
    if let Err(e) = runtime.start().await {
        eprintln!("rvc-ros2dds-bridge: cannot start the Zenoh router: {e}");
        return ExitCode::from(1);
    }
    println!("ready {}", runtime.zid());
    wait_for_stop_signal().await;
    // No runtime.close(): with the plugin's routes alive, Zenoh 1.10.2 panics while they are
    // dropped after the close (an unwrap in its routing tables, then a panic in a destructor:
    // abort). Exiting here stops everything at once; DDS and Zenoh peers see the links go.
    std::process::exit(0)
}

async fn wait_for_stop_signal() {
    use tokio::signal::unix::{signal, SignalKind};
    match (signal(SignalKind::interrupt()), signal(SignalKind::terminate())) {
        (Ok(mut int), Ok(mut term)) => {
            tokio::select! { _ = int.recv() => {}, _ = term.recv() => {} }
        }
        // No signal handlers: fall back to Ctrl-C alone.
        _ => {
            let _ = tokio::signal::ctrl_c().await;
        }
    }
}

/// The configuration must keep both sides of the bridge on this machine (see the header).
fn check_stays_local(config: &zenoh::Config) -> Result<(), String> {
    if config.plugin(PLUGIN).is_none() {
        return Err(format!("no plugins.{PLUGIN} object: the plugin would not start"));
    }
    if json_at(config, "scouting/multicast/enabled") != serde_json::Value::Bool(false) {
        return Err("scouting.multicast.enabled must be false (a test bridge never scouts the LAN)".into());
    }
    for key in ["listen/endpoints", "connect/endpoints"] {
        for endpoint in endpoints(&json_at(config, key)) {
            if !is_local_endpoint(&endpoint) {
                return Err(format!(
                    "{} endpoint '{endpoint}' is not on loopback (tcp/127.0.0.1:PORT, tcp/[::1]:PORT, tcp/localhost:PORT or unixsock-stream/PATH)",
                    key.replace('/', ".")
                ));
            }
        }
    }
    if endpoints(&json_at(config, "listen/endpoints")).is_empty() {
        return Err("listen.endpoints is empty: a router would listen on every interface by default".into());
    }
    match std::env::var("CYCLONEDDS_URI") {
        Ok(v) if !v.trim().is_empty() => Ok(()),
        _ => Err("CYCLONEDDS_URI is not set: the plugin's CycloneDDS must be pinned to the loopback interface".into()),
    }
}

fn json_at(config: &zenoh::Config, key: &str) -> serde_json::Value {
    config
        .get_json(key)
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok())
        .unwrap_or(serde_json::Value::Null)
}

/// Endpoints may be a plain list or a per-mode object ({router: [...], peer: [...]}).
fn endpoints(value: &serde_json::Value) -> Vec<String> {
    match value {
        serde_json::Value::Array(items) => items.iter().filter_map(|v| v.as_str().map(String::from)).collect(),
        serde_json::Value::Object(modes) => modes.values().flat_map(endpoints).collect(),
        _ => Vec::new(),
    }
}

fn is_local_endpoint(endpoint: &str) -> bool {
    // Drop the endpoint's metadata/config parts (after '?' or '#').
    let locator = endpoint.split(['?', '#']).next().unwrap_or("");
    if locator.starts_with("unixsock-stream/") {
        return true;
    }
    let Some(address) = locator.strip_prefix("tcp/") else { return false };
    let host = match address.rsplit_once(':') {
        Some((h, _port)) => h,
        None => return false,
    };
    matches!(host, "127.0.0.1" | "[::1]" | "localhost")
}
