#include "common/net/dds_security.h"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace microdex::net {
namespace {

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const { Free(p); }
};
using BioPtr = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using X509Ptr = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using KeyPtr = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using StorePtr = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;
using StoreCtxPtr = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX, X509_STORE_CTX_free>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

[[noreturn]] void Fail(const std::string& dir, const std::string& file, const std::string& why) {
  ERR_clear_error();
  throw std::runtime_error("security '" + dir + "': " + file + ": " + why);
}

std::string OpenSslError() {
  const unsigned long code = ERR_get_error();  // NOLINT(google-runtime-int): OpenSSL's type
  if (code == 0) return "unknown OpenSSL error";
  char buf[256];
  ERR_error_string_n(code, buf, sizeof buf);
  return buf;
}

BioPtr OpenFile(const std::string& dir, const std::string& name) {
  BioPtr bio(BIO_new_file((dir + "/" + name).c_str(), "r"));
  if (!bio) Fail(dir, name, "cannot read it");
  return bio;
}

X509Ptr ReadCertificate(const std::string& dir, const std::string& name) {
  BioPtr bio = OpenFile(dir, name);
  X509Ptr cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) Fail(dir, name, "not a PEM certificate (" + OpenSslError() + ")");
  return cert;
}

// The S/MIME document `name` must be signed by `ca` (the check Fast DDS makes: the signer
// among the given certificates only, no chain).
void CheckSigned(const std::string& dir, const std::string& name, X509* ca,
                 const std::string& ca_name) {
  BioPtr in = OpenFile(dir, name);
  BIO* content = nullptr;
  Pkcs7Ptr p7(SMIME_read_PKCS7(in.get(), &content));
  BioPtr content_owner(content);
  if (!p7) Fail(dir, name, "not an S/MIME signed document (" + OpenSslError() + ")");
  STACK_OF(X509)* signers = sk_X509_new_null();
  sk_X509_push(signers, ca);
  BioPtr out(BIO_new(BIO_s_mem()));
  const int ok = PKCS7_verify(p7.get(), signers, nullptr, content, out.get(),
                              PKCS7_TEXT | PKCS7_NOVERIFY | PKCS7_NOINTERN);
  sk_X509_free(signers);
  if (ok != 1) {
    Fail(dir, name,
         "its signature does not verify against " + ca_name +
             " (the document was changed after signing, or signed by another course's CA: " +
             OpenSslError() + ")");
  }
}

}  // namespace

SecurityFiles LoadSecurityFiles(const std::string& dir_arg) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir_arg, ec)) {
    throw std::runtime_error("security '" + dir_arg +
                             "': not a directory (deploy/security/make-course creates one per "
                             "station and instructor)");
  }
  SecurityFiles f;
  f.dir = fs::absolute(dir_arg).lexically_normal().string();
  if (f.dir.size() > 1 && f.dir.back() == '/') f.dir.pop_back();
  const std::string& dir = f.dir;
  for (const char* name : {"identity_ca.pem", "cert.pem", "key.pem", "permissions_ca.pem",
                           "governance.p7s", "permissions.p7s", "course"}) {
    if (!fs::is_regular_file(dir + "/" + name, ec)) Fail(dir, name, "missing");
  }
  f.identity_ca = dir + "/identity_ca.pem";
  f.certificate = dir + "/cert.pem";
  f.private_key = dir + "/key.pem";
  f.permissions_ca = dir + "/permissions_ca.pem";
  f.governance = dir + "/governance.p7s";
  f.permissions = dir + "/permissions.p7s";

  std::ifstream course(dir + "/course");
  std::getline(course, f.course);
  if (f.course.empty() || f.course.size() > 48 ||
      f.course.find_first_not_of(
          "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") !=
          std::string::npos) {
    Fail(dir, "course", "expected one line of 1..48 characters A-Z a-z 0-9 . _ -");
  }

  // The identity: issued by the identity CA, and the key is its key.
  const X509Ptr identity_ca = ReadCertificate(dir, "identity_ca.pem");
  const X509Ptr cert = ReadCertificate(dir, "cert.pem");
  StorePtr store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), identity_ca.get());
  StoreCtxPtr ctx(X509_STORE_CTX_new());
  X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr);
  if (X509_verify_cert(ctx.get()) != 1) {
    Fail(dir, "cert.pem",
         std::string("not issued by identity_ca.pem (") +
             X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get())) + ")");
  }
  {
    BioPtr bio = OpenFile(dir, "key.pem");
    KeyPtr key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
    if (!key) Fail(dir, "key.pem", "not a PEM private key without passphrase");
    if (X509_check_private_key(cert.get(), key.get()) != 1) {
      Fail(dir, "key.pem", "not the key of cert.pem");
    }
  }
  // The documents: signed by the permissions CA.
  const X509Ptr permissions_ca = ReadCertificate(dir, "permissions_ca.pem");
  CheckSigned(dir, "governance.p7s", permissions_ca.get(), "permissions_ca.pem");
  CheckSigned(dir, "permissions.p7s", permissions_ca.get(), "permissions_ca.pem");
  return f;
}

std::vector<std::pair<std::string, std::string>> SecurityProperties(const SecurityFiles& f) {
  const auto uri = [](const std::string& path) { return "file://" + path; };
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", uri(f.identity_ca)},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", uri(f.certificate)},
      {"dds.sec.auth.builtin.PKI-DH.private_key", uri(f.private_key)},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", uri(f.permissions_ca)},
      {"dds.sec.access.builtin.Access-Permissions.governance", uri(f.governance)},
      {"dds.sec.access.builtin.Access-Permissions.permissions", uri(f.permissions)},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

std::string SecurePartition(const std::string& course, const std::string& station_id) {
  return course + "/" + (station_id.empty() ? std::string("*") : station_id);
}

}  // namespace microdex::net
