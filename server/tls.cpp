#include "server/tls.h"

#include <openssl/pem.h>
#include <openssl/x509.h>

#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

using Bio = std::unique_ptr<BIO, decltype(&BIO_free)>;
using Certificate = std::unique_ptr<X509, decltype(&X509_free)>;
using PrivateKey = std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)>;

Bio MemoryBio(const std::string& pem) {
  return Bio(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())), &BIO_free);
}

// A PEM file's text; errors name the configuration field and the file.
absl::StatusOr<std::string> ReadPem(const std::string& path, const char* field) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  if (in) text << in.rdbuf();
  if (!in || text.str().empty()) {
    return absl::InvalidArgumentError(absl::StrCat("configuration: ", field, " ", path,
                                                   ": cannot read it (missing, empty or "
                                                   "not readable by this user)"));
  }
  return text.str();
}

// The first certificate of a PEM text, or null.
Certificate FirstCertificate(const std::string& pem) {
  Bio bio = MemoryBio(pem);
  return Certificate(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr), &X509_free);
}

}  // namespace

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> PortCredentials(
    const v1::DaemonConfig& config) {
  if (config.tls_cert_file().empty()) return grpc::InsecureServerCredentials();
  absl::StatusOr<std::string> cert = ReadPem(config.tls_cert_file(), "tls_cert_file");
  if (!cert.ok()) return cert.status();
  absl::StatusOr<std::string> key = ReadPem(config.tls_key_file(), "tls_key_file");
  if (!key.ok()) return key.status();

  // The certificate and its key, which must belong together
  Certificate certificate = FirstCertificate(*cert);
  if (!certificate) {
    return absl::InvalidArgumentError(absl::StrCat(
        "configuration: tls_cert_file ", config.tls_cert_file(), " holds no PEM certificate"));
  }
  Bio key_bio = MemoryBio(*key);
  PrivateKey private_key(PEM_read_bio_PrivateKey(key_bio.get(), nullptr, nullptr, nullptr),
                         &EVP_PKEY_free);
  if (!private_key) {
    return absl::InvalidArgumentError(
        absl::StrCat("configuration: tls_key_file ", config.tls_key_file(),
                     " holds no PEM private key (an encrypted key is not supported)"));
  }
  if (X509_check_private_key(certificate.get(), private_key.get()) != 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("configuration: tls_key_file ", config.tls_key_file(),
                     " is not the key of the certificate in ", config.tls_cert_file()));
  }
  grpc::SslServerCredentialsOptions options;
  options.pem_key_cert_pairs.push_back({*key, *cert});

  // Mutual TLS: every client shows a certificate that chains to these CAs
  if (!config.tls_client_ca_file().empty()) {
    absl::StatusOr<std::string> ca = ReadPem(config.tls_client_ca_file(), "tls_client_ca_file");
    if (!ca.ok()) return ca.status();
    if (!FirstCertificate(*ca)) {
      return absl::InvalidArgumentError(absl::StrCat("configuration: tls_client_ca_file ",
                                                     config.tls_client_ca_file(),
                                                     " holds no PEM certificate"));
    }
    options.pem_root_certs = *ca;
    options.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(options);
}

}  // namespace fenestra
