#pragma once
/// DDS Security of a participant: which keystore and identity (enclave) it uses, the start-up check of
/// that enclave's files, and the Fast DDS plugin properties. No Fast DDS headers: the config loader
/// reads and validates a SecurityConfig without linking Fast DDS.
///
/// A keystore is the sros2 layout that scripts/make_keystore.sh writes: `KEYSTORE/enclaves/NAME/` holds
/// one identity's cert.pem, key.pem, identity_ca.cert.pem, permissions_ca.cert.pem, governance.p7s and
/// permissions.p7s (docs/SECURITY.md).
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shapeform::dds {

/// DDS Security settings of a participant (keys security.*; part of the participant factory's input).
struct SecurityConfig {
  bool enabled = false;  ///< authentication (PKI-DH), access control (permissions) and encryption (AES-GCM)
  std::string keystore;  ///< keystore folder (sros2 layout); required when enabled
  /// Enclave under `keystore/enclaves/`; empty = derived from the process's role and id (supervisor,
  /// agent_K with K the first hosted agent id, viewer for read-only monitors).
  std::string identity;
};

/// A security set-up that cannot work: a missing, unreadable, expired or mismatched file, a keystore or
/// enclave that does not exist. The message names the file and the fix. Programs exit 2 on it (a bad
/// configuration), never run unsecured instead.
class SecurityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Whether `name` may name an enclave: 1..64 of letters, digits, `_`, `-`, `.`, not starting with `.`
/// (a folder directly under enclaves/, never a path out of it).
bool valid_identity(const std::string& name);

/// The enclave folder: keystore/enclaves/identity, absolute.
std::string enclave_dir(const SecurityConfig& s);

/// Checks the enclave of an enabled SecurityConfig before any participant is created. Throws
/// SecurityError naming the file for: a keystore or enclave folder that does not exist, any of the six
/// files missing or unreadable, a certificate or key that does not parse, a certificate (or CA) that
/// has expired or is not valid yet, a key that does not belong to cert.pem, cert.pem not issued by
/// identity_ca.cert.pem, governance.p7s or permissions.p7s whose signature does not verify against
/// permissions_ca.cert.pem. Uses the system clock (validity dates).
void check_enclave(const SecurityConfig& s);

/// The Fast DDS participant properties of an enabled SecurityConfig: builtin.PKI-DH with the enclave's
/// identity CA, certificate and key, builtin.Access-Permissions with its permissions CA, governance and
/// permissions, builtin.AES-GCM-GMAC (file:// URIs of absolute paths). Checks nothing.
std::vector<std::pair<std::string, std::string>> security_properties(const SecurityConfig& s);

/// "secured as agent_3 (keystore /run/ks)" or "unsecured". Never throws.
std::string describe(const SecurityConfig& s);

}  // namespace shapeform::dds
