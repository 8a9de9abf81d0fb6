//! Where the simulator's frames go: a SocketCAN interface or an iceoryx2 service.

use crate::SimError;

/// A frame sink.
pub trait Transport {
    /// Sends one frame (`fd`: as a CAN FD frame, else classic).
    fn send(&mut self, can_id: u16, bytes: &[u8], fd: bool) -> Result<(), SimError>;
    /// Pushes out anything batched (called after every chunk of samples and at the end).
    fn flush(&mut self) -> Result<(), SimError>;
}

#[cfg(feature = "can")]
pub mod can {
    use super::Transport;
    use crate::SimError;
    use socketcan::{
        CanDataFrame, CanFdFrame, CanFdSocket, CanInterface, EmbeddedFrame, Socket, StandardId,
    };
    use std::io::ErrorKind;
    use std::time::Duration;

    /// Blocking SocketCAN sender (the simulator needs no async runtime).
    pub struct CanTransport {
        interface: String,
        socket: CanFdSocket,
    }

    /// Creates `interface` as a vcan with FD MTU and brings it up (needs CAP_NET_ADMIN; for
    /// tests in a VM). An interface that already exists is left as it is.
    pub fn create_vcan(interface: &str) -> Result<(), SimError> {
        if CanInterface::open(interface).is_ok() {
            return Ok(());
        }
        let fail = |e: String| SimError::Interface {
            interface: interface.to_string(),
            detail: e,
        };
        let iface = CanInterface::create_vcan(interface, None)
            .map_err(|e| fail(format!("create vcan: {e}")))?;
        iface
            .set_mtu(socketcan::nl::Mtu::Fd)
            .map_err(|e| fail(format!("set FD MTU: {e}")))?;
        iface
            .bring_up()
            .map_err(|e| fail(format!("bring up: {e}")))?;
        Ok(())
    }

    impl CanTransport {
        pub fn open(interface: &str) -> Result<CanTransport, SimError> {
            let socket = CanFdSocket::open(interface).map_err(|e| SimError::Interface {
                interface: interface.to_string(),
                detail: format!("open CAN FD raw socket: {e}"),
            })?;
            Ok(CanTransport {
                interface: interface.to_string(),
                socket,
            })
        }
    }

    impl Transport for CanTransport {
        fn send(&mut self, can_id: u16, bytes: &[u8], fd: bool) -> Result<(), SimError> {
            let id = StandardId::new(can_id).ok_or(SimError::Frame {
                can_id: u32::from(can_id),
                detail: "not an 11-bit identifier".into(),
            })?;
            let bad = |what: &str| SimError::Frame {
                can_id: u32::from(can_id),
                detail: format!("{what} frame cannot hold {} bytes", bytes.len()),
            };
            // A full transmit queue (ENOBUFS) is back-pressure, not an error: wait and retry.
            let mut attempts = 0u32;
            loop {
                let result = if fd {
                    let mut frame = CanFdFrame::new(id, bytes).ok_or_else(|| bad("CAN FD"))?;
                    frame.set_brs(true);
                    self.socket.write_frame(&frame)
                } else {
                    let frame = CanDataFrame::new(id, bytes).ok_or_else(|| bad("classic"))?;
                    self.socket.write_frame(&frame)
                };
                match result {
                    Ok(()) => return Ok(()),
                    Err(e)
                        if (e.kind() == ErrorKind::WouldBlock
                            || e.raw_os_error() == Some(libc_enobufs()))
                            && attempts < 10_000 =>
                    {
                        attempts += 1;
                        std::thread::sleep(Duration::from_micros(200));
                    }
                    Err(e) => {
                        return Err(SimError::Interface {
                            interface: self.interface.clone(),
                            detail: format!("write frame {can_id:#05x}: {e}"),
                        })
                    }
                }
            }
        }

        fn flush(&mut self) -> Result<(), SimError> {
            Ok(())
        }
    }

    const fn libc_enobufs() -> i32 {
        105 // ENOBUFS on Linux
    }
}

#[cfg(feature = "shm")]
pub mod shm {
    use super::Transport;
    use crate::SimError;
    use bearing_iox::{
        backpressure, create_node, open_data_service, open_event_service, FrameBatch, IoxSettings,
        ServiceNames, ShmError, WireFrame,
    };
    use iceoryx2::prelude::*;
    use iceoryx2::sample_mut::SampleMut;
    use std::time::{Duration, Instant};

    /// Publishes frames in batches of up to 64 on `bearingd/accel/<sensor>` and notifies
    /// `.../wake` after each batch. Zero-copy: the batch is a sample loaned from the shared
    /// memory (`loan_uninit` + `write_payload` of an empty header), the frames are written into
    /// it in place, and sending only hands its offset to the subscribers.
    pub struct ShmTransport {
        service: String,
        /// The batch being filled, in shared memory.
        loaned: Option<SampleMut<ipc::Service, FrameBatch, ()>>,
        publisher: iceoryx2::port::publisher::Publisher<ipc::Service, FrameBatch, ()>,
        wake: iceoryx2::port::notifier::Notifier<ipc::Service>,
        ready: iceoryx2::port::listener::Listener<ipc::Service>,
        _node: Node<ipc::Service>,
        pub batches_sent: u64,
    }

    impl ShmTransport {
        /// `block`: wait for a full subscriber (lossless) instead of discarding.
        pub fn open(
            sensor: &str,
            iox: &IoxSettings,
            block: bool,
        ) -> Result<ShmTransport, SimError> {
            let names = ServiceNames::for_sensor(sensor);
            let shm = |e: ShmError| SimError::Shm(e.to_string());
            let node = create_node(iox).map_err(shm)?;
            let data = open_data_service(&node, &names).map_err(shm)?;
            let publisher = data
                .publisher_builder()
                .backpressure_strategy(backpressure(block))
                .create()
                .map_err(|e| SimError::Shm(format!("{}: create publisher: {e:?}", names.data)))?;
            let wake = open_event_service(&node, &names.wake)
                .map_err(shm)?
                .notifier_builder()
                .create()
                .map_err(|e| SimError::Shm(format!("{}: create notifier: {e:?}", names.wake)))?;
            let ready = open_event_service(&node, &names.ready)
                .map_err(shm)?
                .listener_builder()
                .create()
                .map_err(|e| SimError::Shm(format!("{}: create listener: {e:?}", names.ready)))?;
            Ok(ShmTransport {
                service: names.data,
                loaned: None,
                publisher,
                wake,
                ready,
                _node: node,
                batches_sent: 0,
            })
        }

        /// Waits until a subscriber says it is connected, or fails after `timeout`.
        pub fn wait_ready(&self, timeout: Duration) -> Result<(), SimError> {
            let deadline = Instant::now() + timeout;
            loop {
                let mut got = false;
                let _ = self
                    .ready
                    .timed_wait(|_| got = true, Duration::from_millis(50));
                if got {
                    return Ok(());
                }
                if Instant::now() >= deadline {
                    return Err(SimError::Shm(format!(
                        "{}: no subscriber said ready within {:.1} s",
                        self.service,
                        timeout.as_secs_f64()
                    )));
                }
            }
        }
    }

    impl Transport for ShmTransport {
        fn send(&mut self, can_id: u16, bytes: &[u8], _fd: bool) -> Result<(), SimError> {
            let frame = WireFrame::new(u32::from(can_id), bytes).ok_or(SimError::Frame {
                can_id: u32::from(can_id),
                detail: format!("{} bytes do not fit a wire frame", bytes.len()),
            })?;
            if self
                .loaned
                .as_ref()
                .is_some_and(|sample| sample.payload().is_full())
            {
                self.flush()?;
            }
            let sample = match self.loaned.as_mut() {
                Some(sample) => sample,
                None => {
                    let sample = self
                        .publisher
                        .loan_uninit()
                        .map_err(|e| SimError::Shm(format!("{}: loan: {e:?}", self.service)))?
                        .write_payload(FrameBatch::default());
                    self.loaned.insert(sample)
                }
            };
            sample.payload_mut().push(frame);
            Ok(())
        }

        fn flush(&mut self) -> Result<(), SimError> {
            let Some(sample) = self.loaned.take() else {
                return Ok(());
            };
            // With a waiting publisher (the default) this waits for room in the subscriber's
            // buffer: back-pressure, nothing lost.
            sample
                .send()
                .map_err(|e| SimError::Shm(format!("{}: send: {e:?}", self.service)))?;
            self.batches_sent += 1;
            let _ = self.wake.notify();
            Ok(())
        }
    }
}
