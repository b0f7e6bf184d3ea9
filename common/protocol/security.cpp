#include "protocol/security.hpp"

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

namespace shapeform::dds {
namespace {

namespace fs = std::filesystem;

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const { Free(p); }
};
using Bio = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using X509Ptr = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using KeyPtr = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using StorePtr = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;
using StoreCtx = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX, X509_STORE_CTX_free>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

/// The enclave's files, by their sros2 names.
constexpr const char* kCert = "cert.pem";
constexpr const char* kKey = "key.pem";
constexpr const char* kIdentityCa = "identity_ca.cert.pem";
constexpr const char* kPermissionsCa = "permissions_ca.cert.pem";
constexpr const char* kGovernance = "governance.p7s";
constexpr const char* kPermissions = "permissions.p7s";

const std::string kRemake = " (make keys with scripts/make_keystore.sh, docs/SECURITY.md)";

[[noreturn]] void fail(const std::string& what) { throw SecurityError("security: " + what); }

/// OpenSSL's first queued error as text ("" when none), clearing the queue.
std::string ssl_error() {
  const unsigned long e = ERR_get_error();
  ERR_clear_error();
  if (e == 0) return "";
  char buf[256];
  ERR_error_string_n(e, buf, sizeof buf);
  return std::string(": ") + buf;
}

/// The whole file, or SecurityError naming it (missing, a folder, unreadable).
std::string read_all(const fs::path& p) {
  std::error_code ec;
  if (!fs::exists(p, ec)) fail(p.string() + " does not exist" + kRemake);
  if (!fs::is_regular_file(p, ec)) fail(p.string() + " is not a regular file");
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  if (!(in && os << in.rdbuf())) fail("cannot read " + p.string() + " (permissions?)");
  return os.str();
}

Bio memory_bio(const std::string& text) {
  Bio b(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
  if (!b) fail("out of memory");
  return b;
}

std::string asn1_time(const ASN1_TIME* t) {
  Bio b(BIO_new(BIO_s_mem()));
  if (!b || ASN1_TIME_print(b.get(), t) != 1) return "?";
  BUF_MEM* mem = nullptr;
  BIO_get_mem_ptr(b.get(), &mem);
  return std::string(mem->data, mem->length);
}

/// A PEM certificate that is valid now, or SecurityError naming the file.
X509Ptr load_certificate(const fs::path& p) {
  const std::string text = read_all(p);
  X509Ptr cert(PEM_read_bio_X509(memory_bio(text).get(), nullptr, nullptr, nullptr));
  if (!cert) fail(p.string() + " is not a PEM certificate" + ssl_error());
  if (X509_cmp_current_time(X509_get0_notAfter(cert.get())) <= 0) {
    fail(p.string() + " expired on " + asn1_time(X509_get0_notAfter(cert.get())) +
         ": make new keys (scripts/make_keystore.sh into a new folder) and deploy them");
  }
  if (X509_cmp_current_time(X509_get0_notBefore(cert.get())) >= 0) {
    fail(p.string() + " is not valid before " + asn1_time(X509_get0_notBefore(cert.get())) +
         " (is this host's clock right?)");
  }
  return cert;
}

StorePtr store_of(X509* ca) {
  StorePtr store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), ca) != 1) fail("cannot build a certificate store" + ssl_error());
  return store;
}

/// Throws unless `signed_file` (S/MIME, as `openssl smime -sign -text` writes) verifies against `ca`.
void verify_signed(const fs::path& signed_file, X509* ca, const fs::path& ca_file) {
  const std::string text = read_all(signed_file);
  BIO* content = nullptr;
  Pkcs7Ptr p7(SMIME_read_PKCS7(memory_bio(text).get(), &content));
  Bio content_owner(content);
  if (!p7) fail(signed_file.string() + " is not an S/MIME signed document" + ssl_error());
  const StorePtr store = store_of(ca);
  Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) != 1) {
    fail(signed_file.string() + ": its signature does not verify against " + ca_file.string() + ssl_error() +
         " (sign it with that authority's key: scripts/make_keystore.sh)");
  }
}

}  // namespace

bool valid_identity(const std::string& name) {
  if (name.empty() || name.size() > 64 || name.front() == '.') return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

std::string enclave_dir(const SecurityConfig& s) {
  std::error_code ec;
  const fs::path keystore = fs::absolute(s.keystore, ec);
  return ((ec ? fs::path(s.keystore) : keystore) / "enclaves" / s.identity).lexically_normal().string();
}

void check_enclave(const SecurityConfig& s) {
  std::error_code ec;
  if (s.keystore.empty()) fail("security.keystore is empty: name a keystore folder" + kRemake);
  if (!fs::is_directory(s.keystore, ec)) {
    fail("security.keystore: no keystore folder " + s.keystore + kRemake);
  }
  if (!valid_identity(s.identity)) {
    fail("security.identity: \"" + s.identity + "\" cannot name an enclave (letters, digits, _ - .)");
  }
  const fs::path dir = enclave_dir(s);
  if (!fs::is_directory(dir, ec)) {
    fail("security.identity: no enclave " + s.identity + " in " + s.keystore + "/enclaves (add it: " +
         "scripts/make_keystore.sh " + s.keystore + " --enclave " + s.identity + ", or --agents N)");
  }
  const X509Ptr identity_ca = load_certificate(dir / kIdentityCa);
  const X509Ptr permissions_ca = load_certificate(dir / kPermissionsCa);
  const X509Ptr cert = load_certificate(dir / kCert);

  const std::string key_text = read_all(dir / kKey);
  KeyPtr key(PEM_read_bio_PrivateKey(memory_bio(key_text).get(), nullptr, nullptr, nullptr));
  if (!key) fail((dir / kKey).string() + " is not a PEM private key without a password" + ssl_error());
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    ERR_clear_error();
    fail((dir / kKey).string() + " does not belong to " + (dir / kCert).string() +
         " (mismatched: take both from one enclave)");
  }

  const StorePtr store = store_of(identity_ca.get());
  StoreCtx ctx(X509_STORE_CTX_new());
  if (!ctx || X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr) != 1) {
    fail("cannot verify certificates" + ssl_error());
  }
  if (X509_verify_cert(ctx.get()) != 1) {
    fail((dir / kCert).string() + " was not issued by " + (dir / kIdentityCa).string() + " (" +
         X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get())) + ")");
  }
  verify_signed(dir / kGovernance, permissions_ca.get(), dir / kPermissionsCa);
  verify_signed(dir / kPermissions, permissions_ca.get(), dir / kPermissionsCa);
}

std::vector<std::pair<std::string, std::string>> security_properties(const SecurityConfig& s) {
  const std::string dir = "file://" + enclave_dir(s) + "/";
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", dir + kIdentityCa},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", dir + kCert},
      {"dds.sec.auth.builtin.PKI-DH.private_key", dir + kKey},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", dir + kPermissionsCa},
      {"dds.sec.access.builtin.Access-Permissions.governance", dir + kGovernance},
      {"dds.sec.access.builtin.Access-Permissions.permissions", dir + kPermissions},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

std::string describe(const SecurityConfig& s) {
  if (!s.enabled) return "unsecured";
  return "secured as " + (s.identity.empty() ? std::string("(no identity)") : s.identity) + " (keystore " +
         s.keystore + ")";
}

}  // namespace shapeform::dds
