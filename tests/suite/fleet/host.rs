//! The Python Sparkplug B host (`tests/python/sparkplug_subscriber.py`) as a child process: it
//! writes every decoded message as a JSON line (read here to wait for events), publishes a
//! primary host's STATE when told on its stdin, and at the end of its stdin checks the Sparkplug
//! rules and prints a summary.

use super::broker::{Mosquitto, HOST_PASSWORD, HOST_USER};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

pub fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

pub struct Host {
    child: Child,
    out: PathBuf,
    lines: mpsc::Receiver<String>,
}

impl Host {
    /// Starts the host and waits until it is subscribed. `rebirth_after`: send an NCMD rebirth
    /// after this many DDATA (0: never).
    pub fn start(broker: &Mosquitto, dir: &Path, rebirth_after: u32) -> Host {
        let python = bearingd_testdata::python_sparkplug().expect("checked by NodeSetup::prepare");
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let out = dir.join("host-messages.jsonl");
        let mut child = Command::new(python)
            .arg(root.join("tests/python/sparkplug_subscriber.py"))
            .args(["--port", &broker.port.to_string()])
            .arg("--cafile")
            .arg(broker.ca())
            .args(["--username", HOST_USER, "--password", HOST_PASSWORD])
            .arg("--proto")
            .arg(root.join("proto/sparkplug_b.proto"))
            .arg("--out")
            .arg(&out)
            .args(["--rebirth-after", &rebirth_after.to_string()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the Python Sparkplug host");
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        let host = Host { child, out, lines };
        match host.lines.recv_timeout(Duration::from_secs(40)) {
            Ok(line) if line == "READY" => host,
            other => panic!(
                "the Python host did not subscribe: {other:?}\n{}",
                broker.log()
            ),
        }
    }

    /// Every message received so far.
    pub fn messages(&self) -> Vec<Value> {
        let mut text = String::new();
        if let Ok(mut f) = std::fs::File::open(&self.out) {
            let _ = f.read_to_string(&mut text);
        }
        text.lines()
            .filter_map(|l| serde_json::from_str(l).ok())
            .collect()
    }

    /// Waits until `done` holds for the messages received; panics with what came after
    /// `timeout_s` seconds.
    pub fn wait_for(
        &self,
        what: &str,
        timeout_s: u64,
        done: impl Fn(&[Value]) -> bool,
    ) -> Vec<Value> {
        let deadline = Instant::now() + Duration::from_secs(timeout_s);
        loop {
            let messages = self.messages();
            if done(&messages) {
                return messages;
            }
            if Instant::now() > deadline {
                let topics: Vec<String> = messages
                    .iter()
                    .map(|m| format!("{} seq {}", m["topic"], m["seq"]))
                    .collect();
                panic!(
                    "waited {timeout_s} s for {what}; the host received {} messages: {topics:?}",
                    messages.len()
                );
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// Publishes `payload` as the STATE of primary host `host_id` (`spBv1.0/STATE/<id>`, QoS 1,
    /// retained if `retain`) and waits for the broker's acknowledgement.
    pub fn publish_state(&mut self, host_id: &str, retain: bool, payload: &str) {
        use std::io::Write;
        let retain = if retain { "retain" } else { "once" };
        let stdin = self.child.stdin.as_mut().expect("the host's stdin");
        writeln!(stdin, "state {host_id} {retain} {payload}").expect("write to the host");
        stdin.flush().expect("write to the host");
        match self.lines.recv_timeout(Duration::from_secs(20)) {
            Ok(line) if line == "PUBLISHED" => {}
            other => panic!("the host did not publish the STATE {payload:?}: {other:?}"),
        }
    }

    /// Ends the host (closes its stdin) and returns its summary.
    pub fn finish(mut self) -> Value {
        drop(self.child.stdin.take());
        let line = self
            .lines
            .recv_timeout(Duration::from_secs(30))
            .expect("the host's summary");
        let _ = self.child.wait();
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("summary {line:?}: {e}"))
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
