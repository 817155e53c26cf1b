//! Where a results store is: an SQLite file (a path), or a PostgreSQL
//! database (`postgres://user@host:port/db`, `postgresql://` too), with
//! TLS as its URL asks (libpq's `sslmode` and `sslrootcert`) and its
//! password never shown.

use super::db::DbError;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// A store's place, as `--store` and `PPMC_STORE` give it.
#[derive(Debug, Clone, PartialEq)]
pub enum Location {
    File(PathBuf),
    Server(Server),
}

impl Location {
    /// A `postgres://` or `postgresql://` URL is a server; anything else a
    /// file.
    pub fn of(given: &Path) -> Result<Location, String> {
        match given.to_str() {
            Some(s) if s.starts_with("postgres://") || s.starts_with("postgresql://") => {
                Server::parse(s).map(Location::Server)
            }
            _ => Ok(Location::File(given.to_path_buf())),
        }
    }

    /// How messages name it: the path, or the URL without its password.
    pub fn shown(&self) -> String {
        match self {
            Location::File(p) => p.display().to_string(),
            Location::Server(s) => s.shown.clone(),
        }
    }
}

/// libpq's `sslmode`, as far as a store needs it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TlsMode {
    /// No TLS.
    Disable,
    /// TLS where the server offers it, its certificate not checked
    /// (libpq's default).
    Prefer,
    /// TLS or no connection; the certificate checked against
    /// `sslrootcert` when one is given, as libpq does.
    Require,
    /// TLS, the certificate signed by `sslrootcert`'s authority.
    VerifyCa,
    /// As `VerifyCa`, and issued to the host named in the URL.
    VerifyFull,
}

/// A PostgreSQL database.
#[derive(Clone, PartialEq)]
pub struct Server {
    /// The URL as the client library takes it (without `sslmode` and
    /// `sslrootcert`, which ppmc applies itself).
    url: String,
    /// The URL without its password, for every message.
    pub shown: String,
    pub tls: TlsMode,
    pub root_cert: Option<PathBuf>,
}

impl std::fmt::Debug for Server {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Never the password: only what every message shows.
        f.debug_struct("Server")
            .field("shown", &self.shown)
            .field("tls", &self.tls)
            .field("root_cert", &self.root_cert)
            .finish()
    }
}

impl Server {
    pub fn parse(url: &str) -> Result<Server, String> {
        let bad = |why: &str| format!("{}: {why}", redact(url));
        let (scheme, rest) = url
            .split_once("://")
            .ok_or_else(|| bad("not a postgres:// URL"))?;
        // The query starts after the user part, which ends at the last
        // `@` (a password may hold `?`).
        let from = rest.rfind('@').map_or(0, |at| at + 1);
        let (head, query) = match rest[from..].find('?') {
            Some(q) => (&rest[..from + q], &rest[from + q + 1..]),
            None => (rest, ""),
        };
        let mut tls = TlsMode::Prefer;
        let mut root_cert = None;
        let mut kept = Vec::new();
        for pair in query.split('&').filter(|p| !p.is_empty()) {
            let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
            match k {
                "sslmode" => {
                    tls = match v {
                        "disable" => TlsMode::Disable,
                        "allow" | "prefer" => TlsMode::Prefer,
                        "require" => TlsMode::Require,
                        "verify-ca" => TlsMode::VerifyCa,
                        "verify-full" => TlsMode::VerifyFull,
                        _ => {
                            return Err(bad(&format!(
                            "sslmode={v}: give disable, prefer, require, verify-ca or verify-full"
                        )))
                        }
                    }
                }
                "sslrootcert" => root_cert = Some(PathBuf::from(percent_decode(v))),
                _ => kept.push(pair),
            }
        }
        if matches!(tls, TlsMode::VerifyCa | TlsMode::VerifyFull) && root_cert.is_none() {
            return Err(bad(
                "sslmode=verify-ca and verify-full need sslrootcert=FILE (the authority's certificate, PEM)",
            ));
        }
        let mut url = format!("{scheme}://{head}");
        if !kept.is_empty() {
            url = format!("{url}?{}", kept.join("&"));
        }
        // The client library's own reading, now, so that a malformed URL
        // is refused before any work.
        url.parse::<postgres::Config>()
            .map_err(|e| bad(&format!("not a PostgreSQL URL ({e})")))?;
        Ok(Server {
            shown: redact(&url),
            url,
            tls,
            root_cert,
        })
    }

    /// Connects, bounded in time (`connect_timeout` in the URL, else 10 s),
    /// with the user and password from `PGUSER`/`USER` and `PGPASSWORD`
    /// where the URL gives none, as libpq does.
    pub(crate) fn connect(&self) -> Result<postgres::Client, DbError> {
        let mut config: postgres::Config = self
            .url
            .parse()
            .map_err(|e| DbError::new(format!("not a PostgreSQL URL ({e})")))?;
        if config.get_user().is_none() {
            let user = ["PGUSER", "USER"]
                .iter()
                .find_map(|v| std::env::var(v).ok().filter(|u| !u.is_empty()))
                .unwrap_or_else(|| "postgres".into());
            config.user(&user);
        }
        if config.get_password().is_none() {
            if let Ok(p) = std::env::var("PGPASSWORD") {
                config.password(&p);
            }
        }
        if config.get_connect_timeout().is_none() {
            config.connect_timeout(Duration::from_secs(10));
        }
        config.ssl_mode(match self.tls {
            TlsMode::Disable => postgres::config::SslMode::Disable,
            TlsMode::Prefer => postgres::config::SslMode::Prefer,
            _ => postgres::config::SslMode::Require,
        });
        let tls = tokio_postgres_rustls::MakeRustlsConnect::new(self.tls_config()?);
        Ok(config.connect(tls)?)
    }

    fn tls_config(&self) -> Result<rustls::ClientConfig, DbError> {
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let verifier: Arc<dyn rustls::client::danger::ServerCertVerifier> =
            match (&self.root_cert, self.tls) {
                // As libpq: `prefer` (and `allow`) never check.
                (Some(file), TlsMode::Require | TlsMode::VerifyCa | TlsMode::VerifyFull) => {
                    let roots = Arc::new(read_roots(file)?);
                    let webpki = rustls::client::WebPkiServerVerifier::builder_with_provider(
                        roots,
                        provider.clone(),
                    )
                    .build()
                    .map_err(|e| DbError::new(format!("sslrootcert: {e}")))?;
                    Arc::new(tls::Checked {
                        webpki,
                        names: self.tls == TlsMode::VerifyFull,
                    })
                }
                _ => Arc::new(tls::Unchecked(provider.clone())),
            };
        Ok(rustls::ClientConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .map_err(|e| DbError::new(format!("TLS: {e}")))?
            .dangerous()
            .with_custom_certificate_verifier(verifier)
            .with_no_client_auth())
    }
}

/// The certificates of a PEM file, as trusted roots.
fn read_roots(file: &Path) -> Result<rustls::RootCertStore, DbError> {
    use rustls::pki_types::{pem::PemObject, CertificateDer};
    let fail =
        |e: &dyn std::fmt::Display| DbError::new(format!("sslrootcert {}: {e}", file.display()));
    let mut roots = rustls::RootCertStore::empty();
    for cert in CertificateDer::pem_file_iter(file).map_err(|e| fail(&e))? {
        roots
            .add(cert.map_err(|e| fail(&e))?)
            .map_err(|e| fail(&e))?;
    }
    if roots.is_empty() {
        return Err(fail(&"no certificate in it"));
    }
    Ok(roots)
}

/// `%XX` decoded (a path in a URL's query).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).copied().and_then(hex),
            b.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A URL as messages show it: the scheme, the user and the host, port and
/// database, and nothing else. The user part ends at the URL's last `@`
/// (a password may hold `/`, `?` or `@` unescaped, which the client library
/// takes), and the whole query goes (a password may be given there too,
/// under a percent-encoded key): nothing of a password can be shown.
pub fn redact(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return "(a store URL that does not read)".to_string();
    };
    let (user, after) = match rest.rsplit_once('@') {
        Some((userinfo, after)) => (
            format!("{}@", userinfo.split_once(':').map_or(userinfo, |(u, _)| u)),
            after,
        ),
        None => (String::new(), rest),
    };
    let place = after.split_once('?').map_or(after, |(p, _)| p);
    format!("{scheme}://{user}{place}")
}

/// The two ways a server's certificate is taken.
mod tls {
    use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
    use rustls::crypto::{verify_tls12_signature, verify_tls13_signature, CryptoProvider};
    use rustls::pki_types::{CertificateDer, ServerName, UnixTime};
    use rustls::{CertificateError, DigitallySignedStruct, Error, SignatureScheme};
    use std::sync::Arc;

    /// `sslmode=prefer` or `require` with no authority to check against:
    /// encrypted, the certificate taken as it comes (libpq does the same).
    /// The handshake's signatures are still checked.
    #[derive(Debug)]
    pub(super) struct Unchecked(pub Arc<CryptoProvider>);

    /// Checked against the authority of `sslrootcert`; the host's name
    /// too for `verify-full`.
    #[derive(Debug)]
    pub(super) struct Checked {
        pub webpki: Arc<rustls::client::WebPkiServerVerifier>,
        pub names: bool,
    }

    impl ServerCertVerifier for Unchecked {
        fn verify_server_cert(
            &self,
            _: &CertificateDer<'_>,
            _: &[CertificateDer<'_>],
            _: &ServerName<'_>,
            _: &[u8],
            _: UnixTime,
        ) -> Result<ServerCertVerified, Error> {
            Ok(ServerCertVerified::assertion())
        }

        fn verify_tls12_signature(
            &self,
            message: &[u8],
            cert: &CertificateDer<'_>,
            dss: &DigitallySignedStruct,
        ) -> Result<HandshakeSignatureValid, Error> {
            verify_tls12_signature(
                message,
                cert,
                dss,
                &self.0.signature_verification_algorithms,
            )
        }

        fn verify_tls13_signature(
            &self,
            message: &[u8],
            cert: &CertificateDer<'_>,
            dss: &DigitallySignedStruct,
        ) -> Result<HandshakeSignatureValid, Error> {
            verify_tls13_signature(
                message,
                cert,
                dss,
                &self.0.signature_verification_algorithms,
            )
        }

        fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
            self.0.signature_verification_algorithms.supported_schemes()
        }
    }

    impl ServerCertVerifier for Checked {
        fn verify_server_cert(
            &self,
            end_entity: &CertificateDer<'_>,
            intermediates: &[CertificateDer<'_>],
            server_name: &ServerName<'_>,
            ocsp: &[u8],
            now: UnixTime,
        ) -> Result<ServerCertVerified, Error> {
            match self
                .webpki
                .verify_server_cert(end_entity, intermediates, server_name, ocsp, now)
            {
                // verify-ca: the authority signed it, for whatever name.
                Err(Error::InvalidCertificate(
                    CertificateError::NotValidForName
                    | CertificateError::NotValidForNameContext { .. },
                )) if !self.names => Ok(ServerCertVerified::assertion()),
                other => other,
            }
        }

        fn verify_tls12_signature(
            &self,
            message: &[u8],
            cert: &CertificateDer<'_>,
            dss: &DigitallySignedStruct,
        ) -> Result<HandshakeSignatureValid, Error> {
            self.webpki.verify_tls12_signature(message, cert, dss)
        }

        fn verify_tls13_signature(
            &self,
            message: &[u8],
            cert: &CertificateDer<'_>,
            dss: &DigitallySignedStruct,
        ) -> Result<HandshakeSignatureValid, Error> {
            self.webpki.verify_tls13_signature(message, cert, dss)
        }

        fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
            self.webpki.supported_verify_schemes()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_password_is_never_shown() {
        for (url, shown) in [
            (
                "postgres://lab:s3cret@db.lab:5433/results",
                "postgres://lab@db.lab:5433/results",
            ),
            (
                "postgresql://lab@db/results?password=s3cret&application_name=x",
                "postgresql://lab@db/results",
            ),
            (
                "postgres://127.0.0.1:1/db?pass%77ord=s3cret",
                "postgres://127.0.0.1:1/db",
            ),
            // A password with `/`, `?` and `@` in it, as the client takes it.
            (
                "postgres://lab:pa/s?s@s3cret@127.0.0.1:1/db",
                "postgres://lab@127.0.0.1:1/db",
            ),
            ("postgres://db/results", "postgres://db/results"),
        ] {
            assert_eq!(redact(url), shown);
            let s = Server::parse(url).expect("parses");
            assert_eq!(s.shown, shown);
            assert!(!format!("{s:?}").contains("s3cret"));
        }
        let e = Server::parse("postgres://lab:s3cret@db/results?sslmode=sometimes")
            .expect_err("refused");
        assert!(
            e.contains("sslmode=sometimes") && !e.contains("s3cret"),
            "{e}"
        );
    }

    #[test]
    fn the_url_asks_for_tls_as_libpq_reads_it() {
        // A `?` in the password is not the query's start.
        let s = Server::parse("postgres://u:p?w@h/db?sslmode=disable").expect("parses");
        assert_eq!(s.tls, TlsMode::Disable);
        let s = Server::parse("postgres://u@h/db?sslmode=verify-full&sslrootcert=%2Ftmp%2Fca.pem")
            .expect("parses");
        assert_eq!(s.tls, TlsMode::VerifyFull);
        assert_eq!(s.root_cert.as_deref(), Some(Path::new("/tmp/ca.pem")));
        assert_eq!(
            s.url, "postgres://u@h/db",
            "ppmc applies its TLS settings itself"
        );
        assert_eq!(
            Server::parse("postgres://u@h/db").expect("parses").tls,
            TlsMode::Prefer
        );
        assert!(Server::parse("postgres://u@h/db?sslmode=verify-ca")
            .expect_err("no authority")
            .contains("sslrootcert"));
        assert!(matches!(
            Location::of(Path::new("results.db")).expect("a file"),
            Location::File(_)
        ));
    }
}
