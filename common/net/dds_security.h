#pragma once
// DDS Security for a participant (`--security DIR`, deploy/security/README.md): the files of
// one identity, checked before Fast DDS sees them, and the participant properties that turn on
// Fast DDS's builtin plugins (PKI-DH authentication, Access-Permissions, AES-GCM-GMAC).
//
// Partitions carry the per-station permissions: the permissions language grants a topic
// within partitions, and every station shares each topic (keyed by station_id), so a secure
// station publishes and subscribes only in partition COURSE/STATION and the instructor in
// COURSE/* (which matches every station's partition). A station identity's grant names its
// own partition only, so it can neither write into nor read from another station's.

#include <string>
#include <utility>
#include <vector>

namespace microdex::net {

// The files make-course writes into an identity's directory.
struct SecurityFiles {
  std::string dir;  // absolute
  std::string identity_ca, certificate, private_key;
  std::string permissions_ca, governance, permissions;
  std::string course;  // the course name (DIR/course): the first part of the partitions
};

// Reads DIR and checks, with OpenSSL, what Fast DDS would later refuse without saying why:
// every file present; cert.pem issued by identity_ca.pem and matching key.pem;
// governance.p7s and permissions.p7s S/MIME signed by permissions_ca.pem (a tampered or
// foreign document fails here). Throws std::runtime_error("security 'DIR': FILE: why").
SecurityFiles LoadSecurityFiles(const std::string& dir);

// The participant properties (name, value) of the builtin plugins for these files.
std::vector<std::pair<std::string, std::string>> SecurityProperties(const SecurityFiles& files);

// The partition a secure participant uses: COURSE/STATION for a station (or the device
// driver of a station), COURSE/* for the instructor (station empty).
std::string SecurePartition(const std::string& course, const std::string& station_id);

}  // namespace microdex::net
