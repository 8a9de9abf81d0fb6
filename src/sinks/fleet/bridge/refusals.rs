//! A refusal by the broker in words, with what to check: the CONNACK's and the PUBACK's reason
//! codes (apart from `bridge.rs` to keep that file readable).

use crate::config::FleetConfig;
use rumqttc::v5::mqttbytes::v5::{ConnectReturnCode, PubAckReason};

/// A CONNACK refusal in words, with what to check.
pub(super) fn refusal(code: ConnectReturnCode, config: &FleetConfig) -> String {
    let user = config.username.as_deref().unwrap_or("(none)");
    match code {
        ConnectReturnCode::BadUserNamePassword => format!(
            "REFUSED the connection: {code:?} (the user name or password is wrong); check \
             fleet.username ({user}) and fleet.password_file against the broker's password file"
        ),
        // mosquitto answers a wrong password with this code under MQTT 5.
        ConnectReturnCode::NotAuthorized => format!(
            "REFUSED the connection: {code:?} (the user name or password is wrong, or the user \
             may not connect or not publish this node's death certificate \
             spBv1.0/{}/NDEATH/{}); check fleet.username ({user}) and fleet.password_file \
             against the broker's password file, and fleet.node_id against its ACL",
            config.group_id, config.node_id
        ),
        ConnectReturnCode::ClientIdentifierNotValid | ConnectReturnCode::BadClientId => format!(
            "REFUSED the connection: {code:?}; check fleet.client_id ({})",
            config.client_id
        ),
        ConnectReturnCode::Banned => {
            format!("REFUSED the connection: {code:?}; ask the broker's administrator")
        }
        code => format!("REFUSED the connection: {code:?}"),
    }
}

/// The MQTT 5 reason code number of a PUBACK reason.
pub(super) fn puback_code(reason: PubAckReason) -> String {
    let code: u8 = match reason {
        PubAckReason::Success => 0x00,
        PubAckReason::NoMatchingSubscribers => 0x10,
        PubAckReason::UnspecifiedError => 0x80,
        PubAckReason::ImplementationSpecificError => 0x83,
        PubAckReason::NotAuthorized => 0x87,
        PubAckReason::TopicNameInvalid => 0x90,
        PubAckReason::PacketIdentifierInUse => 0x91,
        PubAckReason::QuotaExceeded => 0x97,
        PubAckReason::PayloadFormatInvalid => 0x99,
    };
    format!("0x{code:02x}")
}
