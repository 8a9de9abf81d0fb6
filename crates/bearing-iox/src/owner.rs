//! Who owns an iceoryx2 service, as the kernel attests it (issue 32: authentic alerts).
//!
//! iceoryx2 0.10 records no user id: a service's attributes and a node's name are written by
//! whoever created them, so they can name things but never prove anything. What the kernel
//! does attest is the owner of the service's static file (`<root>/services/<prefix><hash>
//! .service`, made by the creator) and the user of a live process (`/proc/<pid>/status`). This
//! module reads both without opening the service, so the daemon can refuse a service someone
//! else made, and a subscriber can refuse a service or a publisher of the wrong user.

use crate::{node_config, service_name, IoxSettings, ShmError};
use iceoryx2::node::NodeView as _;
use iceoryx2::prelude::*;
use iceoryx2::service::static_config::StaticConfig;
use std::fmt;
use std::os::unix::fs::MetadataExt;
use std::path::PathBuf;

/// What the kernel says about one node registered at a service.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeInfo {
    /// Its process id (as the node recorded it), if iceoryx2 could read its details.
    pub pid: Option<i32>,
    /// Its executable's file name, as the node recorded it (for naming only).
    pub executable: String,
    /// The effective uid of process `pid` from `/proc`, when it runs.
    pub uid: Option<u32>,
    /// iceoryx2's verdict on the node's process.
    pub state: NodeLiveness,
}

/// iceoryx2's [`NodeState`] without its handle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeLiveness {
    Alive,
    Dead,
    /// This user may not look at it (another user's node): treated as hostile.
    Inaccessible,
    Undefined,
}

/// A service's owners: the user who created its static file and the nodes using it.
#[derive(Debug, Clone)]
pub struct ServiceOwners {
    pub service: String,
    /// `<root>/services/<prefix><hash>.service`.
    pub static_file: PathBuf,
    /// Its owner, `None` when it cannot be looked at (or is not a regular file).
    pub file_uid: Option<u32>,
    pub nodes: Vec<NodeInfo>,
}

impl fmt::Display for ServiceOwners {
    /// "held by pid 812 (python3, uid 1000), created by uid 1000 (<file>)".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut holders = Vec::new();
        for node in &self.nodes {
            let pid = node
                .pid
                .map_or("an unknown pid".into(), |p| format!("pid {p}"));
            let uid = node
                .uid
                .map_or("uid unknown".into(), |u| format!("uid {u}"));
            let state = match node.state {
                NodeLiveness::Alive => "",
                NodeLiveness::Dead => ", dead",
                NodeLiveness::Inaccessible => ", not visible to this user",
                NodeLiveness::Undefined => ", in an undefined state",
            };
            holders.push(format!("{pid} ({}, {uid}{state})", node.executable));
        }
        let held = if holders.is_empty() {
            "held by no node".to_string()
        } else {
            format!("held by {}", holders.join(", "))
        };
        let created = self
            .file_uid
            .map_or("an unknown user".into(), |u| format!("uid {u}"));
        write!(
            f,
            "{held}, created by {created} ({})",
            self.static_file.display()
        )
    }
}

impl ServiceOwners {
    /// The alive nodes whose process runs as another user than `uid`, or cannot be confirmed.
    pub fn foreign_nodes(&self, uid: u32) -> impl Iterator<Item = &NodeInfo> {
        self.nodes.iter().filter(move |n| match n.state {
            NodeLiveness::Alive => n.uid != Some(uid),
            NodeLiveness::Dead => false,
            NodeLiveness::Inaccessible | NodeLiveness::Undefined => true,
        })
    }
}

/// The effective uid of process `pid`, from `/proc/<pid>/status` (its `Uid:` line; not the
/// owner of `/proc/<pid>`, which shows root for a process that is not dumpable).
pub fn process_uid(pid: i32) -> Option<u32> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1))
        .and_then(|euid| euid.parse().ok())
}

/// The effective uid of this process.
pub fn own_uid() -> Option<u32> {
    process_uid(std::process::id() as i32)
}

/// Looks at service `name` of `pattern` without opening it: `None` when it does not exist,
/// else its static config (the shape its creator chose) and its owners.
pub fn inspect(
    settings: &IoxSettings,
    name: &str,
    pattern: MessagingPattern,
) -> Result<Option<(StaticConfig, ServiceOwners)>, ShmError> {
    let config = node_config(settings)?;
    let details = ipc::Service::details(&service_name(name)?, &config, pattern).map_err(|e| {
        ShmError::Service {
            service: name.to_string(),
            detail: format!("cannot look at it: {e:?}"),
        }
    })?;
    let Some(details) = details else {
        return Ok(None);
    };
    let static_file = PathBuf::from(config.global.service_dir().to_string()).join(format!(
        "{}{}{}",
        config.global.prefix,
        details.static_details.service_hash().as_str(),
        config.global.service.static_config_storage_suffix
    ));
    let file_uid = std::fs::symlink_metadata(&static_file)
        .ok()
        .filter(|m| m.file_type().is_file())
        .map(|m| m.uid());
    let nodes = details
        .dynamic_details
        .map(|d| d.nodes.iter().map(node_info).collect())
        .unwrap_or_default();
    let owners = ServiceOwners {
        service: name.to_string(),
        static_file,
        file_uid,
        nodes,
    };
    Ok(Some((details.static_details, owners)))
}

/// What a creator may do with a service name (see [`claim`]).
#[derive(Debug)]
pub enum Claim {
    /// No such service: create it (exclusively; losing a race is a [`Taken`]).
    Create,
    /// Ours already: made by this user, of the shape we need, no other user's node on it (a
    /// previous run of ours, kept alive by its subscribers). Open it; a second publisher is
    /// still refused by its `max_publishers`.
    Reopen(ServiceOwners),
}

/// A service a creator must not use: someone else's, or of another shape.
#[derive(Debug, Clone)]
pub struct Taken {
    pub owners: ServiceOwners,
    /// Why it is not ours ("another shape", "created by uid 1001").
    pub why: String,
}

/// Decides whether this process may use service `name`: [`Claim::Create`] when it does not
/// exist, [`Claim::Reopen`] when its static file is this user's, `fits` accepts its shape and no
/// node of another user is on it; else [`Taken`]. Never opens the service.
pub fn claim(
    settings: &IoxSettings,
    name: &str,
    pattern: MessagingPattern,
    fits: impl Fn(&StaticConfig) -> bool,
) -> Result<Result<Claim, Taken>, ShmError> {
    let Some((config, owners)) = inspect(settings, name, pattern)? else {
        return Ok(Ok(Claim::Create));
    };
    let uid = own_uid();
    let why = if owners.file_uid.is_none() || owners.file_uid != uid {
        "it was created by another user"
    } else if owners
        .foreign_nodes(uid.unwrap_or(u32::MAX))
        .next()
        .is_some()
    {
        "a process of another user (or one this user cannot see) uses it"
    } else if !fits(&config) {
        "it has another shape than bearingd's (another program made it)"
    } else {
        return Ok(Ok(Claim::Reopen(owners)));
    };
    Ok(Err(Taken {
        owners,
        why: why.to_string(),
    }))
}

/// The kernel's view of one node.
pub fn node_info<S: iceoryx2::service::Service>(state: &NodeState<S>) -> NodeInfo {
    let (details, state) = match state {
        NodeState::Alive(v) => (v.details().as_ref(), NodeLiveness::Alive),
        NodeState::Dead(v) => (v.details().as_ref(), NodeLiveness::Dead),
        NodeState::Inaccessible(_) => (None, NodeLiveness::Inaccessible),
        NodeState::Undefined(_) => (None, NodeLiveness::Undefined),
    };
    let pid = details.map(|d| d.process_id().value());
    NodeInfo {
        pid,
        executable: details.map_or("unknown".into(), |d| d.executable().to_string()),
        uid: match state {
            NodeLiveness::Alive => pid.and_then(process_uid),
            _ => None,
        },
        state,
    }
}

/// The node id of a live node, to match it with a port's `node_id`.
pub fn alive_node_id<S: iceoryx2::service::Service>(
    state: &NodeState<S>,
) -> Option<iceoryx2::identifiers::UniqueNodeId> {
    match state {
        NodeState::Alive(v) => Some(*v.id()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uid_of_this_process_is_read_from_proc() {
        let uid = own_uid().unwrap();
        let meta = std::fs::metadata("/proc/self/status").unwrap();
        assert_eq!(uid, meta.uid());
        assert_eq!(process_uid(-1), None);
    }

    #[test]
    fn an_owner_sentence_names_the_pid_program_uid_and_file() {
        let owners = ServiceOwners {
            service: "bearingd/alerts".into(),
            static_file: "/r/services/x.service".into(),
            file_uid: Some(1000),
            nodes: vec![NodeInfo {
                pid: Some(812),
                executable: "python3".into(),
                uid: Some(1000),
                state: NodeLiveness::Alive,
            }],
        };
        assert_eq!(
            owners.to_string(),
            "held by pid 812 (python3, uid 1000), created by uid 1000 (/r/services/x.service)"
        );
        assert_eq!(owners.foreign_nodes(1000).count(), 0);
        assert_eq!(owners.foreign_nodes(0).count(), 1);
    }
}
