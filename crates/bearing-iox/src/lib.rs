//! bearingd's iceoryx2 conventions, in one place for the daemon and for the programs that
//! publish to it (`firmware-sim`): the service names under `bearingd/`, the settings every node
//! is created with (file prefix, root path, no signal handling), the shapes of the data and
//! event services, and the sample payload ([`FrameBatch`]).
//!
//! Why a crate of its own: a publisher must agree with the daemon on every one of these, and
//! a sensor simulator should not have to link the whole daemon to do so.
//!
//! Feature `iceoryx2` (default): the node and service helpers and the payload's `ZeroCopySend`
//! derive. Without it only the names and settings remain (what the daemon's config needs when
//! it is built without iceoryx2).

#![forbid(unsafe_code)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

#[cfg(feature = "iceoryx2")]
pub mod owner;
pub mod payload;

pub use payload::{
    BatchError, FrameBatch, WireFrame, FRAMES_PER_BATCH, FRAME_BATCH_VERSION, MAX_FRAME_LEN,
};

#[cfg(feature = "iceoryx2")]
use iceoryx2::port::backpressure_strategy::BackpressureStrategy;
#[cfg(feature = "iceoryx2")]
use iceoryx2::prelude::*;

/// Every bearingd service name starts with this.
pub const SERVICE_ROOT: &str = "bearingd/";

/// Prefix of a sensor's sample service: `bearingd/accel/<sensor>`.
pub const SENSOR_SERVICE_PREFIX: &str = "bearingd/accel/";

/// The environment variable that sets the iceoryx2 file prefix of the daemon and of
/// `bearingd alerts` (for isolated tests; unset in production).
pub const PREFIX_ENV: &str = "BEARINGD_IOX_PREFIX";

/// Batches a sample subscriber's iceoryx2 buffer holds.
pub const SUBSCRIBER_BUFFER: usize = 64;

/// iceoryx2 settings shared by publisher and subscriber.
#[derive(Debug, Clone, Default)]
pub struct IoxSettings {
    /// File-name prefix of every iceoryx2 resource (iceoryx2 `global.prefix`); `None` keeps
    /// iceoryx2's default. Different prefixes never see each other: used for test isolation.
    pub prefix: Option<String>,
    /// iceoryx2 root path (`global.root-path`); `None` keeps the default.
    pub root_path: Option<String>,
}

impl IoxSettings {
    /// The daemon's settings: the root path `root` (`outputs.iceoryx2_root`) and the file
    /// prefix from [`PREFIX_ENV`] when it is set.
    pub fn with_root(root: &std::path::Path) -> IoxSettings {
        IoxSettings {
            prefix: std::env::var(PREFIX_ENV).ok(),
            root_path: Some(root.display().to_string()),
        }
    }

    /// How messages name the root: the path, or "iceoryx2's default".
    pub fn root_name(&self) -> &str {
        self.root_path.as_deref().unwrap_or("iceoryx2's default")
    }
}

/// Why an iceoryx2 port could not be set up. Messages name the service.
#[derive(Debug, thiserror::Error)]
pub enum ShmError {
    #[error("iceoryx2: invalid setting {what} = {value:?}")]
    Setting { what: &'static str, value: String },
    #[error("iceoryx2: cannot create the node: {0}")]
    Node(String),
    #[error("iceoryx2 service {service}: {detail}")]
    Service { service: String, detail: String },
    #[error("iceoryx2 source thread: {0}")]
    Thread(String),
}

/// The sample service of `sensor`: `bearingd/accel/<sensor>`.
pub fn sensor_service(sensor: &str) -> String {
    format!("{SENSOR_SERVICE_PREFIX}{sensor}")
}

/// The sensor name of a sample service, if it has the form `bearingd/accel/<sensor>`.
pub fn sensor_of_service(service: &str) -> Option<&str> {
    service.strip_prefix(SENSOR_SERVICE_PREFIX)
}

/// The event service a publisher notifies after each sample of `service`.
pub fn wake_service(service: &str) -> String {
    format!("{service}/wake")
}

/// Service names of one sensor.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    pub data: String,
    pub wake: String,
    pub ready: String,
}

impl ServiceNames {
    pub fn for_sensor(sensor: &str) -> ServiceNames {
        let data = sensor_service(sensor);
        ServiceNames {
            wake: wake_service(&data),
            ready: format!("{data}/ready"),
            data,
        }
    }
}

/// A node of a process that died (`kill -9`, a power cut) without removing its iceoryx2
/// resources, found at start by [`remove_dead_nodes`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeadNode {
    /// Its name, process id and executable, as far as iceoryx2 kept them.
    pub description: String,
    /// `Err` with iceoryx2's reason when its resources could not be removed.
    pub removed: Result<(), String>,
}

#[cfg(feature = "iceoryx2")]
/// Removes the resources (shared memory, its node and service entries under the root) of every
/// dead node under these settings, so that a killed daemon leaves nothing behind once the next
/// starts; returns what was found, to be said. iceoryx2 would also do it silently on the next
/// node's creation; doing it first tells the operator.
pub fn remove_dead_nodes(settings: &IoxSettings) -> Result<Vec<DeadNode>, ShmError> {
    use iceoryx2::node::NodeView as _;
    let config = node_config(settings)?;
    let mut dead = Vec::new();
    Node::<ipc::Service>::list(&config, |state| {
        if let NodeState::Dead(view) = state {
            let description = match view.details() {
                Some(d) => format!(
                    "node {:?} of pid {} ({})",
                    d.name().as_str(),
                    d.process_id(),
                    d.executable()
                ),
                None => format!("node {:?}", view.id()),
            };
            let removed = view
                .try_remove_stale_resources()
                .map_err(|e| format!("{e:?}"));
            dead.push(DeadNode {
                description,
                removed,
            });
        }
        CallbackProgression::Continue
    })
    .map_err(|e| ShmError::Node(format!("cannot list the nodes to find dead ones: {e:?}")))?;
    Ok(dead)
}

#[cfg(feature = "iceoryx2")]
/// iceoryx2's config with bearingd's settings.
fn node_config(settings: &IoxSettings) -> Result<Config, ShmError> {
    let mut config = Config::default();
    if let Some(prefix) = &settings.prefix {
        config.global.prefix = FileName::new(prefix.as_bytes()).map_err(|_| ShmError::Setting {
            what: "prefix",
            value: prefix.clone(),
        })?;
    }
    if let Some(root) = &settings.root_path {
        let path = Path::new(root.as_bytes()).map_err(|_| ShmError::Setting {
            what: "root_path",
            value: root.clone(),
        })?;
        config.global.set_root_path(&path);
    }
    Ok(config)
}

#[cfg(feature = "iceoryx2")]
/// An iceoryx2 node with bearingd's settings, of either variant: `ipc::Service` (ports stay
/// on the thread that made them) or `ipc_threadsafe::Service` (ports shared between threads;
/// the same shared memory, so either end may use the other variant).
pub fn create_node<S: iceoryx2::service::Service>(
    settings: &IoxSettings,
) -> Result<Node<S>, ShmError> {
    let config = node_config(settings)?;
    NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<S>()
        .map_err(|e| ShmError::Node(format!("{e:?}")))
}

#[cfg(feature = "iceoryx2")]
pub fn service_name(name: &str) -> Result<ServiceName, ShmError> {
    ServiceName::new(name).map_err(|e| ShmError::Service {
        service: name.to_string(),
        detail: format!("invalid name: {e:?}"),
    })
}

#[cfg(feature = "iceoryx2")]
/// The data service, with the shape both ends agree on: no safe overflow (a full subscriber
/// buffer is the publisher's decision: wait, or discard and let the receiver count a gap).
pub fn open_data_service(
    node: &Node<ipc::Service>,
    names: &ServiceNames,
) -> Result<
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, FrameBatch, ()>,
    ShmError,
> {
    node.service_builder(&service_name(&names.data)?)
        .publish_subscribe::<FrameBatch>()
        .enable_safe_overflow(false)
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
        .max_publishers(4)
        .max_subscribers(4)
        .open_or_create()
        .map_err(|e| ShmError::Service {
            service: names.data.clone(),
            detail: format!("open or create: {e:?}"),
        })
}

#[cfg(feature = "iceoryx2")]
/// An event service (wake-up or ready).
pub fn open_event_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    name: &str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, ShmError> {
    node.service_builder(&service_name(name)?)
        .event()
        .open_or_create()
        .map_err(|e| ShmError::Service {
            service: name.to_string(),
            detail: format!("open or create: {e:?}"),
        })
}

#[cfg(feature = "iceoryx2")]
/// The publisher's backpressure choice: wait for a full subscriber (`block`, lossless) or
/// discard (the receiver counts a gap).
pub fn backpressure(block: bool) -> BackpressureStrategy {
    if block {
        BackpressureStrategy::RetryUntilDelivered
    } else {
        BackpressureStrategy::DiscardData
    }
}
