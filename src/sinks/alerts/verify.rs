//! A subscriber's checks that the alert service is the daemon's (issue 32): iceoryx2 records no
//! user, so the checks ask the kernel (see `bearing_iox::owner`). The service's static file and
//! its wake event's must be owned by the expected user, the service must take one publisher
//! only (bearingd's shape), and that publisher's process must run as the expected user. What
//! cannot be confirmed (a node this user cannot see, a pid that is gone) fails closed.

use super::payload::Alert;
use crate::iox::owner::{alive_node_id, inspect, process_uid};
use crate::iox::IoxSettings;
use iceoryx2::node::NodeView as _;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2::service::static_config::messaging_pattern::MessagingPattern as Shape;

/// Checks service `name` (opened as `service`) and its wake event `wake` against `uid`; the
/// error says what failed.
pub(super) fn verify_service(
    iox: &IoxSettings,
    name: &str,
    wake: &str,
    service: &PubSubFactory<ipc::Service, Alert, ()>,
    uid: u32,
) -> Result<(), String> {
    for (what, pattern) in [
        (name, MessagingPattern::PublishSubscribe),
        (wake, MessagingPattern::Event),
    ] {
        let Some((config, owners)) = inspect(iox, what, pattern).map_err(|e| e.to_string())? else {
            return Err(format!("{what} vanished while being checked"));
        };
        if owners.file_uid != Some(uid) {
            return Err(format!(
                "{what} is not uid {uid}'s: {owners}; only the daemon's user may create it"
            ));
        }
        let single = match config.messaging_pattern() {
            Shape::PublishSubscribe(ps) => ps.max_publishers() == 1,
            Shape::Event(event) => event.max_notifiers() == 1,
            _ => false,
        };
        if !single {
            return Err(format!(
                "{what} admits more than one sender: bearingd did not make it ({owners})"
            ));
        }
    }
    verify_publisher(service, uid)
}

/// The service's one publisher (if any) runs as `uid`.
fn verify_publisher(
    service: &PubSubFactory<ipc::Service, Alert, ()>,
    uid: u32,
) -> Result<(), String> {
    let dynamic = service.dynamic_config();
    let mut publishers = Vec::new();
    dynamic.list_publishers(|p| {
        publishers.push(p.node_id);
        CallbackProgression::Continue
    });
    if publishers.len() > 1 {
        return Err(format!("{} publishers on it, not one", publishers.len()));
    }
    for node_id in publishers {
        let mut found = None;
        let _ = service.nodes(|state| {
            if alive_node_id(&state) == Some(node_id) {
                if let NodeState::Alive(view) = &state {
                    found = view.details().as_ref().map(|d| {
                        let pid = d.process_id().value();
                        (pid, d.executable().to_string(), process_uid(pid))
                    });
                }
            }
            CallbackProgression::Continue
        });
        match found {
            Some((_, _, Some(publisher_uid))) if publisher_uid == uid => {}
            Some((pid, exe, publisher_uid)) => {
                let who = publisher_uid
                    .map_or("a uid that cannot be read".into(), |u| format!("uid {u}"));
                return Err(format!(
                    "its publisher, pid {pid} ({exe}), runs as {who}, not as uid {uid}"
                ));
            }
            None => {
                return Err(
                    "its publisher's process cannot be confirmed alive and of this user".into(),
                )
            }
        }
    }
    Ok(())
}
