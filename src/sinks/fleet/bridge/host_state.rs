//! The bridge's side of the Sparkplug 3.0 primary host (`fleet.primary_host_id`): the STATE
//! messages the session receives, read by [`PrimaryHost`] (sans-IO), turned into births, a pause,
//! or a notice. Apart from `bridge.rs` to keep that file readable; the gate itself
//! ([`Bridge::may_publish`]) is asked by the births, `pump` and `drained` there.

use super::{now_ms, Bridge};
use crate::sinks::fleet::primary::{PrimaryHost, StateChange};
use rumqttc::v5::mqttbytes::v5::SubscribeReasonCode;

/// Ignored STATE messages said one by one; the rest are counted.
const STATE_WARNINGS: u64 = 5;

impl Bridge {
    /// Whether births and data may go out: always without a primary host, else while it is
    /// online (its STATE); records wait in the queue meanwhile.
    pub(super) fn may_publish(&self) -> bool {
        self.primary.as_ref().is_none_or(PrimaryHost::is_online)
    }

    /// A STATE of the primary host: births when it comes online (then `pump` sends the queued
    /// records), a pause when it goes offline; a stale or unreadable one is said and counted.
    pub(super) fn on_state(&mut self, payload: &[u8]) {
        let Some(primary) = self.primary.as_mut() else {
            return;
        };
        let change = primary.on_state(payload);
        let (id, topic) = (primary.id().to_string(), primary.topic().to_string());
        let pending = self.queue.pending();
        match change {
            StateChange::CameOnline => {
                let next = self.queue.next_number();
                let Some(session) = self.session.as_mut().filter(|s| s.up) else {
                    return;
                };
                // What waited for the host was made before it could see it: historical.
                session.first_live = next;
                (self.notices)(format!(
                    "fleet: primary host {id} is online: births sent, then {pending} queued \
                     records"
                ));
                let births = self.node.births(&self.book, now_ms());
                self.send(births);
            }
            StateChange::WentOffline => (self.notices)(format!(
                "fleet: primary host {id} is offline ({topic}): publishing paused, records wait \
                 in the queue ({pending} now); the MQTT session stays up"
            )),
            StateChange::Unchanged => {}
            StateChange::Stale { timestamp, newest } => self.warn_state(format!(
                "its timestamp {timestamp} is older than the newest seen ({newest}): an old \
                 retained message, or the host's clock went back"
            )),
            StateChange::Unreadable(e) => self.warn_state(e.to_string()),
        }
    }

    /// Says that a STATE was ignored (the first few; a host that keeps sending them is
    /// counted, and the count is in the summary at the stop).
    fn warn_state(&mut self, why: String) {
        let Some(primary) = &self.primary else {
            return;
        };
        let stats = primary.stats();
        let ignored = stats.unreadable + stats.stale;
        if ignored > STATE_WARNINGS {
            return;
        }
        let more = if ignored == STATE_WARNINGS {
            "; further ignored STATE messages are counted, not said (the summary at the stop)"
        } else {
            ""
        };
        let state = if primary.is_online() {
            "online"
        } else {
            "offline"
        };
        let topic = primary.topic().to_string();
        self.report(format!(
            "warning: fleet: a STATE on {topic} ignored: {why}; the host stays {state}{more}"
        ));
    }

    /// The broker's answer to the STATE subscription: a refusal would hold every publish back
    /// for good, so it is said with what to check.
    pub(super) fn on_state_suback(&mut self, codes: &[SubscribeReasonCode]) {
        let Some(primary) = &self.primary else {
            return;
        };
        if let Some(code) = codes
            .iter()
            .find(|c| !matches!(c, SubscribeReasonCode::Success(_)))
        {
            let topic = primary.topic().to_string();
            self.report(format!(
                "fleet: broker {} REFUSED the subscription to {topic}: {code:?}; nothing is \
                 published until this node can read its primary host's STATE; check the \
                 broker's ACL lets user {} read {topic}, and fleet.primary_host_id",
                self.config.broker,
                self.config.username.as_deref().unwrap_or("(anonymous)")
            ));
        }
    }
}
