//! `[outputs]`: directories, the MCAP log's budget, the alert service and the iceoryx2 root.

use super::*;

impl Checker {
    pub(super) fn outputs(
        &mut self,
        raw: &RawOutputs,
        sensors: &[CheckedSensor],
    ) -> Option<OutputConfig> {
        let d = OutputConfig::default();
        let state_dir = self.directory(
            "outputs.state_dir",
            &raw.state_dir,
            &d.state_dir,
            "give the directory for persistent state (baselines, band choices), e.g. \
             state_dir = \"/var/lib/bearingd\"",
        );
        let mcap_dir = self.directory(
            "outputs.mcap_dir",
            &raw.mcap_dir,
            &d.mcap_dir,
            "give the directory for MCAP log files, e.g. mcap_dir = \"/var/log/bearingd\"",
        );
        let max_mb = i64::try_from(d.mcap_max_file_mb).unwrap_or(256);
        let mcap_max_file_mb = self
            .integer(
                "outputs.mcap_max_file_mb",
                &raw.mcap_max_file_mb,
                max_mb,
                1,
                1 << 20,
                "give the size in MiB at which an MCAP file is closed and the next begun, \
                 e.g. mcap_max_file_mb = 256",
            )
            .and_then(|n| u64::try_from(n).ok());
        let mcap_max_file_s = self.number(
            "outputs.mcap_max_file_s",
            &raw.mcap_max_file_s,
            d.mcap_max_file_s,
            Limits::within(1.0, 7.0 * DAY_S),
            "give the age in seconds at which an MCAP file is closed and the next begun, e.g. \
             mcap_max_file_s = 3600",
        );
        let mcap_fsync_interval_s = self.number(
            "outputs.mcap_fsync_interval_s",
            &raw.mcap_fsync_interval_s,
            d.mcap_fsync_interval_s,
            Limits::within(0.0, 3600.0),
            "give the seconds of data between two forced writes of the open MCAP file to the \
             disk (what a power cut can lose), e.g. mcap_fsync_interval_s = 5",
        );
        let budget_fix = "give the disk space in MiB that MCAP files may fill before the \
                          oldest is deleted, at least twice mcap_max_file_mb, e.g. \
                          mcap_disk_budget_mb = 4096";
        let budget = self
            .integer(
                "outputs.mcap_disk_budget_mb",
                &raw.mcap_disk_budget_mb,
                i64::try_from(d.mcap_disk_budget_mb).unwrap_or(4096),
                1,
                i64::MAX,
                budget_fix,
            )
            .and_then(|n| u64::try_from(n).ok());
        let mcap_disk_budget_mb = match (budget, mcap_max_file_mb) {
            (Some(budget), Some(max)) if budget < max.saturating_mul(2) => {
                self.problem(
                    "outputs.mcap_disk_budget_mb",
                    format!(
                        "{budget} MiB is less than twice mcap_max_file_mb (2 × {max} = {} MiB), \
                         but the budget must hold the open file plus at least one finished \
                         one; raise mcap_disk_budget_mb to at least {} or lower \
                         mcap_max_file_mb",
                        max.saturating_mul(2),
                        max.saturating_mul(2),
                    ),
                );
                None
            }
            (budget, _) => budget,
        };
        let alerts_key = "outputs.alerts_service";
        let alerts_fix = "give an iceoryx2 service name under bearingd/, e.g. alerts_service = \
                          \"bearingd/alerts\"";
        let alerts_service = self
            .or_default(
                alerts_key,
                &raw.alerts_service,
                d.alerts_service,
                alerts_fix,
            )
            .and_then(|service| self.service_name(alerts_key, service, alerts_fix))
            .and_then(|service| self.service_name(alerts_key, service, alerts_fix));
        if let Some(service) = &alerts_service {
            for sensor in sensors {
                if sensor.shm_service.as_ref() == Some(service) {
                    let suggestion = if sensor.default_service() == *service {
                        crate::iox::sensor_service("<id>")
                    } else {
                        sensor.default_service()
                    };
                    self.problem(
                        format!("sensors[{}].shm.service", sensor.index),
                        format!(
                            "{service:?} is also outputs.alerts_service, so samples and alerts \
                             would share a service; give the sensor its own, e.g. service = \
                             {suggestion:?}"
                        ),
                    );
                }
            }
        }
        let iceoryx2_root = self.iceoryx2_root(&raw.iceoryx2_root, &d.iceoryx2_root);
        let status_interval_s = self.number(
            "outputs.status_interval_s",
            &raw.status_interval_s,
            d.status_interval_s,
            Limits::above_to(0.0, 3600.0),
            "give how often status is reported, in seconds, e.g. status_interval_s = 5.0",
        );
        let state_save_interval_s = self.number(
            "outputs.state_save_interval_s",
            &raw.state_save_interval_s,
            d.state_save_interval_s,
            Limits::above_to(0.0, 86_400.0),
            "give how often the learned state is saved, in seconds, e.g. \
             state_save_interval_s = 60.0",
        );
        let cpu_wakeup_latency_us = self.cpu_wakeup_latency(&raw.cpu_wakeup_latency_us);
        let cpu_awake_during_analysis = self.or_default(
            "outputs.cpu_awake_during_analysis",
            &raw.cpu_awake_during_analysis,
            d.cpu_awake_during_analysis,
            "give true to keep idle CPUs awake while a block is analysed (alerts reach \
             subscribers sooner) or false, e.g. cpu_awake_during_analysis = true",
        );
        Some(OutputConfig {
            state_dir: state_dir?,
            mcap_dir: mcap_dir?,
            mcap_max_file_mb: mcap_max_file_mb?,
            mcap_max_file_s: mcap_max_file_s?,
            mcap_fsync_interval_s: mcap_fsync_interval_s?,
            mcap_disk_budget_mb: mcap_disk_budget_mb?,
            alerts_service: alerts_service?,
            iceoryx2_root: iceoryx2_root?,
            status_interval_s: status_interval_s?,
            state_save_interval_s: state_save_interval_s?,
            cpu_wakeup_latency_us: cpu_wakeup_latency_us?,
            cpu_awake_during_analysis: cpu_awake_during_analysis?,
        })
    }

    /// `outputs.cpu_wakeup_latency_us`: optional, 0 µs to 1 s.
    fn cpu_wakeup_latency(&mut self, field: &Field<i64>) -> Option<Option<u32>> {
        let key = "outputs.cpu_wakeup_latency_us";
        let fix = "give the longest wake-up latency the CPUs may have while bearingd runs, in \
                   µs (0: idle CPUs poll), e.g. cpu_wakeup_latency_us = 0, or leave the key out";
        match self.get(key, field, fix) {
            Got::Missing => Some(None),
            Got::Invalid => None,
            Got::Value(us) => self
                .integer_in(key, us, 0, 1_000_000, fix)
                .and_then(|us| u32::try_from(us).ok())
                .map(Some),
        }
    }

    pub(super) fn directory(
        &mut self,
        key: &str,
        field: &Field<String>,
        default: &Path,
        fix: &str,
    ) -> Option<PathBuf> {
        let text = self.or_default(key, field, default.to_string_lossy().into_owned(), fix)?;
        if text.trim().is_empty() || text.contains('\0') {
            self.problem(key, format!("{text:?} is not a directory path; {fix}"));
            None
        } else {
            Some(PathBuf::from(text))
        }
    }

    pub(super) fn iceoryx2_root(
        &mut self,
        field: &Field<String>,
        default: &Path,
    ) -> Option<PathBuf> {
        let key = "outputs.iceoryx2_root";
        let fix = "move it to a directory outside /tmp and /var/tmp, e.g. iceoryx2_root = \
                   \"/run/bearingd/iceoryx2\"";
        let path = self.directory(key, field, default, fix)?;
        if !path.is_absolute() {
            self.problem(
                key,
                format!(
                    "{:?} is a relative path, but subscribers in other processes must find the \
                     same directory; give an absolute path, e.g. iceoryx2_root = \
                     \"/run/bearingd/iceoryx2\"",
                    path.display().to_string()
                ),
            );
            return None;
        }
        if path.components().any(|c| c == Component::ParentDir) {
            self.problem(
                key,
                format!(
                    "{:?} contains '..'; give a plain absolute path, e.g. iceoryx2_root = \
                     \"/run/bearingd/iceoryx2\"",
                    path.display().to_string()
                ),
            );
            return None;
        }
        if let Some(tmp) = ["/tmp", "/var/tmp"]
            .into_iter()
            .find(|tmp| path.starts_with(tmp))
        {
            self.problem(
                key,
                format!(
                    "{:?} is under {tmp}: systemd's PrivateTmp= gives the service its own \
                     {tmp}, which would hide iceoryx2's files from subscribers in other \
                     processes; {fix}",
                    path.display().to_string()
                ),
            );
            return None;
        }
        let length = path.as_os_str().len();
        if length > MAX_IOX_ROOT_LEN {
            self.problem(
                key,
                format!(
                    "{:?} is {length} bytes long, more than {MAX_IOX_ROOT_LEN}: iceoryx2 puts \
                     Unix sockets below it whose paths must fit in 108 bytes (a subscriber \
                     could not wait for alerts); {fix}",
                    path.display().to_string()
                ),
            );
            return None;
        }
        Some(path)
    }
}
