//! A real mosquitto for one test: certificates made with openssl, a password file made with
//! mosquitto_passwd, an ACL, and a config, all generated in the test's scratch directory.
//!
//! The broker speaks TLS only, refuses anonymous clients and lets each node publish under its
//! own node id only (`pattern write spBv1.0/+/+/%u`, the user name being the node id). A
//! second listener authenticates clients by certificate (the certificate's CN is the user).
//! Persistence is on and QoS 0 messages are queued for the test's persistent subscriber, so
//! that a broker restart loses nothing on the subscriber's side: what the test checks is the
//! bridge's delivery, not the subscriber's.
//!
//! Shared by the tests and `benches/fleet.rs` (its load test), each of which uses a part.
#![allow(dead_code)]

use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The Sparkplug group of every test.
pub const GROUP: &str = "plant";
/// The test host (subscriber) user, allowed to read everything, to send commands and to publish
/// a primary host's STATE.
pub const HOST_USER: &str = "scada";
pub const HOST_PASSWORD: &str = "host-secret";
/// The load generator of `benches/fleet.rs`: many simulated nodes under group `load`.
pub const LOAD_USER: &str = "loadgen";
pub const LOAD_PASSWORD: &str = "load-secret";

/// A node user and its password (the user name is the node id the ACL allows).
pub struct NodeUser {
    pub name: &'static str,
    pub password: &'static str,
}

pub const NODES: [NodeUser; 2] = [
    NodeUser {
        name: "press-7",
        password: "press-7-secret",
    },
    NodeUser {
        name: "press-8",
        password: "press-8-secret",
    },
];

/// The programs the fleet tests need; under CI=true a missing one fails the test, elsewhere it
/// is said loudly and the test returns.
pub fn tools_present() -> bool {
    let missing: Vec<&str> = ["mosquitto", "mosquitto_passwd", "openssl", "protoc"]
        .into_iter()
        .filter(|tool| {
            Command::new("sh")
                .args([
                    "-c",
                    &format!("command -v {tool} || test -x /usr/sbin/{tool}"),
                ])
                .stdout(Stdio::null())
                .status()
                .map_or(true, |s| !s.success())
        })
        .collect();
    if missing.is_empty() {
        return true;
    }
    let message = format!(
        "the fleet tests need {} (Debian: apt-get install mosquitto mosquitto-clients openssl \
         protobuf-compiler; .ci/run installs them)",
        missing.join(", ")
    );
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{message}");
    }
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "\n**********\nSKIPPING: {message}\n**********\n"
    );
    false
}

fn mosquitto_program() -> &'static str {
    if Path::new("/usr/sbin/mosquitto").exists() {
        "/usr/sbin/mosquitto"
    } else {
        "mosquitto"
    }
}

fn run(program: &str, args: &[&str], dir: &Path) {
    let out = Command::new(program)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {program}: {e}"));
    assert!(
        out.status.success(),
        "{program} {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// A CA, a server certificate for localhost/127.0.0.1, and a client certificate with CN `cn`;
/// EC P-256 keys (quick to make).
fn make_certificates(dir: &Path, client_cn: &str) {
    let ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1"];
    let mut ca = vec!["req", "-x509", "-nodes", "-days", "2"];
    ca.extend(ec);
    ca.extend([
        "-keyout",
        "ca.key",
        "-out",
        "ca.pem",
        "-subj",
        "/CN=bearingd test CA",
        "-addext",
        "basicConstraints=critical,CA:TRUE",
        "-addext",
        "keyUsage=critical,keyCertSign,cRLSign",
    ]);
    run("openssl", &ca, dir);
    // A second CA that signed nothing of this broker: a client trusting it must fail TLS.
    let mut other = ca.clone();
    for arg in other.iter_mut() {
        match *arg {
            "ca.key" => *arg = "other-ca.key",
            "ca.pem" => *arg = "other-ca.pem",
            _ => {}
        }
    }
    run("openssl", &other, dir);
    for (name, cn, ext) in [
        (
            "server",
            "localhost",
            "subjectAltName=DNS:localhost,IP:127.0.0.1\nextendedKeyUsage=serverAuth\n",
        ),
        ("client", client_cn, "extendedKeyUsage=clientAuth\n"),
    ] {
        let mut req = vec!["req", "-nodes"];
        req.extend(ec);
        let key = format!("{name}.key");
        let csr = format!("{name}.csr");
        let subject = format!("/CN={cn}");
        req.extend(["-keyout", &key, "-out", &csr, "-subj", &subject]);
        run("openssl", &req, dir);
        let ext_file = format!("{name}.ext");
        std::fs::write(dir.join(&ext_file), ext).unwrap();
        let pem = format!("{name}.pem");
        run(
            "openssl",
            &[
                "x509",
                "-req",
                "-in",
                &csr,
                "-CA",
                "ca.pem",
                "-CAkey",
                "ca.key",
                "-CAcreateserial",
                "-days",
                "2",
                "-out",
                &pem,
                "-extfile",
                &ext_file,
            ],
            dir,
        );
    }
}

/// A mosquitto with its generated files; stopped (SIGTERM, then SIGKILL) when dropped.
pub struct Mosquitto {
    pub dir: PathBuf,
    /// The TLS listener with user names and passwords.
    pub port: u16,
    /// The TLS listener that authenticates clients by certificate.
    pub cert_port: u16,
    /// The CN of `client.pem`, the user it authenticates as.
    pub client_cn: String,
    child: Option<Child>,
}

impl Mosquitto {
    /// Generates everything in `dir` and starts the broker.
    pub fn start(dir: &Path) -> Mosquitto {
        let dir = dir.join("broker");
        std::fs::create_dir_all(dir.join("db")).unwrap();
        let client_cn = "press-9".to_string();
        make_certificates(&dir, &client_cn);
        let passwords = dir.join("passwd");
        std::fs::write(&passwords, "").unwrap();
        let users = NODES
            .iter()
            .map(|n| (n.name, n.password))
            .chain([(HOST_USER, HOST_PASSWORD), (LOAD_USER, LOAD_PASSWORD)]);
        for (user, password) in users {
            run(
                "mosquitto_passwd",
                &["-b", passwords.to_str().unwrap(), user, password],
                &dir,
            );
        }
        std::fs::write(
            dir.join("acl"),
            format!(
                "# the test host reads everything and may command nodes\n\
                 user {HOST_USER}\n\
                 topic read spBv1.0/#\n\
                 topic write spBv1.0/+/NCMD/#\n\
                 topic write spBv1.0/+/DCMD/#\n\
                 topic write spBv1.0/STATE/#\n\
                 # the load generator's simulated nodes\n\
                 user {LOAD_USER}\n\
                 topic readwrite spBv1.0/load/#\n\
                 # a node publishes under its own node id only, and reads its commands\n\
                 pattern write spBv1.0/+/+/%u\n\
                 pattern write spBv1.0/+/+/%u/#\n\
                 pattern read spBv1.0/+/NCMD/%u\n\
                 pattern read spBv1.0/+/DCMD/%u/#\n\
                 # and every primary host's STATE (Sparkplug 3.0)\n\
                 pattern read spBv1.0/STATE/+\n"
            ),
        )
        .unwrap();
        let port = free_port();
        let cert_port = free_port();
        // /proc/self belongs to the effective user.
        let running_as_root =
            std::os::unix::fs::MetadataExt::uid(&std::fs::metadata("/proc/self").unwrap()) == 0;
        let config = format!(
            "# generated by the fleet test\n\
             {user}\
             per_listener_settings true\n\
             persistence true\n\
             persistence_location {db}/\n\
             queue_qos0_messages true\n\
             max_queued_messages 100000\n\
             max_inflight_messages 100\n\
             log_dest file {log}\n\
             log_type error\nlog_type warning\nlog_type notice\nlog_type information\n\
             connection_messages true\n\
             \n\
             listener {port} 127.0.0.1\n\
             allow_anonymous false\n\
             password_file {passwords}\n\
             acl_file {acl}\n\
             cafile {ca}\n\
             certfile {server_pem}\n\
             keyfile {server_key}\n\
             \n\
             listener {cert_port} 127.0.0.1\n\
             allow_anonymous false\n\
             acl_file {acl}\n\
             cafile {ca}\n\
             certfile {server_pem}\n\
             keyfile {server_key}\n\
             require_certificate true\n\
             use_identity_as_username true\n",
            user = if running_as_root { "user root\n" } else { "" },
            db = dir.join("db").display(),
            log = dir.join("mosquitto.log").display(),
            passwords = passwords.display(),
            acl = dir.join("acl").display(),
            ca = dir.join("ca.pem").display(),
            server_pem = dir.join("server.pem").display(),
            server_key = dir.join("server.key").display(),
        );
        std::fs::write(dir.join("mosquitto.conf"), config).unwrap();
        let mut broker = Mosquitto {
            dir,
            port,
            cert_port,
            client_cn,
            child: None,
        };
        broker.up();
        broker
    }

    /// Starts the broker (again) on the same ports and files, and waits until it listens.
    pub fn up(&mut self) {
        assert!(self.child.is_none(), "the broker is already running");
        let child = Command::new(mosquitto_program())
            .arg("-c")
            .arg(self.dir.join("mosquitto.conf"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start mosquitto");
        self.child = Some(child);
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            if let Some(status) = self
                .child
                .as_mut()
                .and_then(|c| c.try_wait().ok().flatten())
            {
                panic!("mosquitto exited at its start ({status}):\n{}", self.log());
            }
            let both = [self.port, self.cert_port]
                .iter()
                .all(|p| TcpStream::connect(("127.0.0.1", *p)).is_ok());
            if both {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("mosquitto not listening after 10 s:\n{}", self.log());
    }

    /// Stops the broker as its service manager would (SIGTERM: it saves its persistence file).
    pub fn down(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
            let deadline = Instant::now() + Duration::from_secs(10);
            while Instant::now() < deadline {
                if child.try_wait().ok().flatten().is_some() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    /// The broker's process id while it runs (for its CPU time and memory).
    pub fn pid(&self) -> Option<u32> {
        self.child.as_ref().map(Child::id)
    }

    pub fn ca(&self) -> PathBuf {
        self.dir.join("ca.pem")
    }

    /// The broker's log, for failure messages.
    pub fn log(&self) -> String {
        std::fs::read_to_string(self.dir.join("mosquitto.log")).unwrap_or_default()
    }
}

impl Drop for Mosquitto {
    fn drop(&mut self) {
        self.down();
    }
}
