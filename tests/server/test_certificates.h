// Certificates for TLS tests, made by the openssl command: a CA, a server certificate for
// 127.0.0.1 and localhost, and a client certificate, each with its key (EC P-256, PEM).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace fenestra {

struct TestCertificates {
  std::string ca, ca_key;               // the CA that signed both
  std::string server_cert, server_key;  // SAN IP:127.0.0.1, DNS:localhost
  std::string client_cert, client_key;  // CN fenestra-test-client
};

// Writes the certificates and keys into `dir` (which exists) and returns their paths.
inline void MakeTestCertificates(const std::string& dir, TestCertificates* out) {
  const TestCertificates c{dir + "/ca.pem",     dir + "/ca.key",     dir + "/server.pem",
                           dir + "/server.key", dir + "/client.pem", dir + "/client.key"};
  const std::string log = dir + "/openssl.log";
  const std::string key = " -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes -keyout ";
  const std::string sign = " -CA " + c.ca + " -CAkey " + c.ca_key + " -CAcreateserial -days 2";
  for (const std::string& command : {
           "openssl req -x509" + key + c.ca_key + " -out " + c.ca +
               " -days 2 -subj /CN=fenestra-test-ca",
           "openssl req" + key + c.server_key + " -out " + dir + "/server.csr" +
               " -subj /CN=localhost -addext subjectAltName=IP:127.0.0.1,DNS:localhost",
           "openssl x509 -req -in " + dir + "/server.csr" + sign + " -copy_extensions copy -out " +
               c.server_cert,
           "openssl req" + key + c.client_key + " -out " + dir + "/client.csr" +
               " -subj /CN=fenestra-test-client",
           "openssl x509 -req -in " + dir + "/client.csr" + sign + " -out " + c.client_cert,
       }) {
    const int code = std::system((command + " >>" + log + " 2>&1").c_str());
    std::stringstream text;
    text << std::ifstream(log).rdbuf();
    ASSERT_EQ(code, 0) << command << "\n" << text.str();
  }
  *out = c;
}

}  // namespace fenestra
