//! `bearingd run` as a fleet node: a config with one simulated sensor whose outer race is
//! faulty from the start (flags come within seconds) and a `[fleet]` section for the test's
//! broker; the process with its stdout and stderr in files, so that the test can wait for a
//! line while it runs.

use super::broker::{Mosquitto, NodeUser, GROUP};
use bearingd_testdata::{iox_root, python_sparkplug, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A test's scratch directory, once the tools it needs are known to be there.
pub struct NodeSetup {
    pub dir: PathBuf,
}

/// What a node's config says about the broker and the queue.
pub struct NodeConfig {
    /// Names the node's files (config, state, output).
    pub name: String,
    pub node_id: String,
    pub port: u16,
    pub username: Option<String>,
    pub password: String,
    pub ca_file: PathBuf,
    pub client_cert: Option<(PathBuf, PathBuf)>,
    pub queue_max_mb: f64,
    /// `fleet.primary_host_id`: publish only while this host's STATE says online.
    pub primary_host_id: Option<String>,
}

impl NodeSetup {
    /// `None` (said loudly) when mosquitto, openssl, protoc or the Python packages are missing
    /// outside CI; under CI=true that fails the test.
    pub fn prepare(test: &str) -> Option<NodeSetup> {
        if !super::broker::tools_present() {
            return None;
        }
        python_sparkplug()?;
        Some(NodeSetup {
            dir: scratch_dir(test),
        })
    }

    /// Writes the config of a node that logs in as `user` (node id = user name) unless
    /// `change` says otherwise.
    pub fn config(
        &self,
        broker: &Mosquitto,
        user: &NodeUser,
        change: impl FnOnce(&mut NodeConfig),
    ) -> PathBuf {
        let mut c = NodeConfig {
            name: user.name.to_string(),
            node_id: user.name.to_string(),
            port: broker.port,
            username: Some(user.name.to_string()),
            password: user.password.to_string(),
            ca_file: broker.ca(),
            client_cert: None,
            queue_max_mb: 64.0,
            primary_host_id: None,
        };
        change(&mut c);
        let dir = self.dir.join(&c.name);
        std::fs::create_dir_all(&dir).unwrap();
        // Short: iceoryx2's socket paths below it must fit in 108 bytes.
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let iox = iox_root(
            env!("CARGO_TARGET_TMPDIR"),
            &format!("fl{}", COUNTER.fetch_add(1, Ordering::Relaxed)),
        );
        let mut fleet = format!(
            "enabled = true\n\
             broker = \"mqtts://localhost:{port}\"\n\
             group_id = \"{GROUP}\"\n\
             node_id = \"{node}\"\n\
             client_id = \"bearingd-{name}\"\n\
             ca_file = \"{ca}\"\n\
             publish_period_s = 1.0\n\
             keep_alive_s = 5\n\
             queue_max_mb = {queue}\n",
            port = c.port,
            node = c.node_id,
            name = c.name,
            ca = c.ca_file.display(),
            queue = c.queue_max_mb,
        );
        if let Some(user) = &c.username {
            let password_file = dir.join("mqtt-password");
            std::fs::write(&password_file, format!("{}\n", c.password)).unwrap();
            fleet.push_str(&format!(
                "username = \"{user}\"\npassword_file = \"{}\"\n",
                password_file.display()
            ));
        }
        if let Some(id) = &c.primary_host_id {
            fleet.push_str(&format!("primary_host_id = \"{id}\"\n"));
        }
        if let Some((cert, key)) = &c.client_cert {
            fleet.push_str(&format!(
                "client_cert_file = \"{}\"\nclient_key_file = \"{}\"\n",
                cert.display(),
                key.display()
            ));
        }
        let text = format!(
            r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 12800
axes = ["radial"]
bearing = "skf-6205-2rs"
[sensors.speed]
source = "fixed"
rpm = 1772
[sensors.sim]
fault = "outer"
onset_s = 0.0
severity = 2.0

[analysis]
band_period_s = 4.0

[thresholds]
on_delay_s = 1.0

[outputs]
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"

[fleet]
{fleet}"#,
            state = dir.join("state").display(),
            mcap = dir.join("mcap").display(),
            iox = iox.display(),
        );
        let path = dir.join("bearingd.toml");
        std::fs::write(&path, text).unwrap();
        path
    }
}

/// How a node process ended.
pub struct Ended {
    pub success: bool,
    pub stderr: String,
}

/// A running `bearingd run`.
pub struct NodeProcess {
    child: Option<Child>,
    stderr: PathBuf,
}

impl NodeProcess {
    pub fn start(setup: &NodeSetup, config: &Path, extra: &[&str]) -> NodeProcess {
        static RUNS: AtomicUsize = AtomicUsize::new(0);
        let run = RUNS.fetch_add(1, Ordering::Relaxed);
        let stem = config
            .parent()
            .unwrap_or(&setup.dir)
            .join(format!("run-{run}"));
        let stdout = std::fs::File::create(stem.with_extension("out")).unwrap();
        let stderr = stem.with_extension("err");
        let child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
            .args(["run", "--quiet", "--config"])
            .arg(config)
            .args(extra)
            .stdout(stdout)
            .stderr(std::fs::File::create(&stderr).unwrap())
            .stdin(Stdio::null())
            .spawn()
            .expect("start bearingd run");
        NodeProcess {
            child: Some(child),
            stderr,
        }
    }

    pub fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    /// Waits until `done` holds for the stderr so far; returns it.
    pub fn wait_for_stderr(
        &self,
        what: &str,
        timeout_s: u64,
        done: impl Fn(&str) -> bool,
    ) -> String {
        let deadline = Instant::now() + Duration::from_secs(timeout_s);
        loop {
            let text = self.stderr();
            if done(&text) {
                return text;
            }
            assert!(
                Instant::now() < deadline,
                "waited {timeout_s} s for {what} on bearingd's stderr:\n{text}"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// SIGKILL: no clean stop, no DISCONNECT.
    pub fn kill_9(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    /// SIGTERM, as systemd stops it; waits for the exit.
    pub fn terminate(self) -> Ended {
        if let Some(child) = &self.child {
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
        }
        self.wait(30)
    }

    /// Waits for the exit (SIGKILL after `timeout_s`, and the test fails).
    pub fn wait(mut self, timeout_s: u64) -> Ended {
        let mut child = self.child.take().expect("a running node");
        let deadline = Instant::now() + Duration::from_secs(timeout_s);
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                let _ = child.wait();
                panic!(
                    "bearingd did not stop within {timeout_s} s:\n{}",
                    self.stderr()
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        Ended {
            success: status.success(),
            stderr: self.stderr(),
        }
    }
}

impl Drop for NodeProcess {
    fn drop(&mut self) {
        self.kill_9();
    }
}
