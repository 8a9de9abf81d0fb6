//! The TLS client setup of the bridge (the cargo feature `tls`): rustls with the ring provider
//! (no OpenSSL, no aws-lc build), the CA file or the system's roots, and a client certificate.
//! Apart from the bridge's I/O so that the bridge's loop stays readable; the bridge turns a
//! [`TlsProblem`] into its start error.

use crate::config::FleetConfig;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A TLS file or setting that cannot be used: the `fleet.` key, the file, what is wrong.
#[derive(Debug)]
pub struct TlsProblem {
    pub key: &'static str,
    pub path: PathBuf,
    pub problem: String,
}

/// rustls with the ring provider: the CA file's certificates (or the system's roots), and the
/// client certificate when configured.
pub fn client_config(config: &FleetConfig) -> Result<rustls::ClientConfig, TlsProblem> {
    use rustls::pki_types::pem::PemObject;
    use rustls::pki_types::{CertificateDer, PrivateKeyDer};
    let tls_error = |key: &'static str, path: &Path, problem: String| TlsProblem {
        key,
        path: path.to_path_buf(),
        problem,
    };
    let mut roots = rustls::RootCertStore::empty();
    match &config.ca_file {
        Some(path) => {
            let certificates: Vec<CertificateDer> = CertificateDer::pem_file_iter(path)
                .and_then(|i| i.collect::<Result<_, _>>())
                .map_err(|e| tls_error("ca_file", path, format!("not PEM certificates: {e}")))?;
            if certificates.is_empty() {
                return Err(tls_error(
                    "ca_file",
                    path,
                    "holds no certificate (expected -----BEGIN CERTIFICATE-----)".into(),
                ));
            }
            for certificate in certificates {
                roots.add(certificate).map_err(|e| {
                    tls_error("ca_file", path, format!("a certificate is unusable: {e}"))
                })?;
            }
        }
        None => {
            let found = rustls_native_certs::load_native_certs();
            for certificate in found.certs {
                let _ = roots.add(certificate);
            }
            if roots.is_empty() {
                return Err(tls_error(
                    "ca_file",
                    Path::new("(not set)"),
                    "no CA file and no system certificates: give the broker's CA as ca_file".into(),
                ));
            }
        }
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| {
            tls_error(
                "broker",
                Path::new(""),
                format!("no TLS protocol version: {e}"),
            )
        })?
        .with_root_certificates(roots);
    match (&config.client_cert_file, &config.client_key_file) {
        (Some(cert), Some(key)) => {
            let chain: Vec<CertificateDer<'static>> = CertificateDer::pem_file_iter(cert)
                .and_then(|i| i.collect::<Result<_, _>>())
                .map_err(|e| {
                    tls_error(
                        "client_cert_file",
                        cert,
                        format!("not PEM certificates: {e}"),
                    )
                })?;
            let key_der = PrivateKeyDer::from_pem_file(key)
                .map_err(|e| tls_error("client_key_file", key, format!("no private key: {e}")))?;
            builder
                .with_client_auth_cert(chain, key_der)
                .map_err(|e| tls_error("client_key_file", key, format!("unusable: {e}")))
        }
        _ => Ok(builder.with_no_client_auth()),
    }
}
