// check_security_files (security.hpp): the checks Fast DDS makes at participant creation,
// made first with OpenSSL (the library Fast DDS's plugins use) so that the message names
// the file. Fast DDS itself only logs "could not create participant" for most of them.
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/dds/security.hpp"

namespace stepnode::bridge::dds {
namespace {

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const { Free(p); }
};
using Bio = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using Cert = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using Store = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;
using StoreCtx = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX, X509_STORE_CTX_free>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

[[noreturn]] void refuse(const char* key, const std::string& path, const std::string& why) {
  ERR_clear_error();  // OpenSSL's queue would otherwise carry this failure into Fast DDS's next
                      // call
  throw std::invalid_argument("dds.security." + std::string(key) + " " + path + ": " + why);
}

Bio open_file(const char* key, const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) refuse(key, path, "cannot read file");
  Bio bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) refuse(key, path, "cannot read file");
  return bio;
}

Cert read_certificate(const char* key, const std::string& path) {
  Bio bio = open_file(key, path);
  Cert cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) refuse(key, path, "not a PEM X.509 certificate");
  return cert;
}

Store store_of(const Cert& ca) {
  Store store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), ca.get()) != 1)
    throw std::runtime_error("OpenSSL: out of memory");
  return store;
}

// The subject as RFC 2253 prints it, the form permissions documents use.
std::string rfc2253_subject(const Cert& cert) {
  Bio bio(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(bio.get(), X509_get_subject_name(cert.get()), 0, XN_FLAG_RFC2253);
  char* data = nullptr;
  long n = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<size_t>(n));
}

// "CN=a, O=b" and "CN=a,O=b" name the same subject: the attributes, trimmed, in order.
std::vector<std::string> attributes(const std::string& name) {
  std::vector<std::string> parts;
  std::string part;
  auto flush = [&] {
    const size_t b = part.find_first_not_of(' '), e = part.find_last_not_of(' ');
    parts.push_back(b == std::string::npos ? "" : part.substr(b, e - b + 1));
    part.clear();
  };
  for (size_t i = 0; i < name.size(); ++i) {
    if (name[i] == '\\' && i + 1 < name.size()) {
      part += name.substr(i++, 2);  // an escaped comma belongs to the value
    } else if (name[i] == ',') {
      flush();
    } else {
      part += name[i];
    }
  }
  flush();
  return parts;
}

void check_identity(const SecurityFiles& f) {
  Cert ca = read_certificate("identity_ca", f.identity_ca);
  Cert cert = read_certificate("identity_certificate", f.identity_certificate);
  Store store = store_of(ca);
  StoreCtx ctx(X509_STORE_CTX_new());
  if (!ctx || X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr) != 1)
    throw std::runtime_error("OpenSSL: out of memory");
  if (X509_verify_cert(ctx.get()) != 1)
    refuse("identity_certificate", f.identity_certificate,
           std::string("not accepted by identity_ca ") + f.identity_ca + " (" +
               X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get())) + ")");
  Bio bio = open_file("private_key", f.private_key);
  Key key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
  if (!key) refuse("private_key", f.private_key, "not an unencrypted PEM private key");
  if (X509_check_private_key(cert.get(), key.get()) != 1)
    refuse("private_key", f.private_key,
           "is not the key of identity_certificate " + f.identity_certificate);
}

// The document's text when the permissions CA signed it (S/MIME, as `openssl smime -sign`).
std::string signed_text(const char* key, const std::string& path, const Cert& ca,
                        const std::string& ca_path) {
  Bio bio = open_file(key, path);
  BIO* content_raw = nullptr;
  Pkcs7 p7(SMIME_read_PKCS7(bio.get(), &content_raw));
  Bio content(content_raw);
  if (!p7)
    refuse(key, path, "not an S/MIME signed document (sign it with openssl smime -sign -text)");
  Store store = store_of(ca);
  Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) != 1)
    refuse(key, path, "signature not accepted by permissions_ca " + ca_path);
  char* data = nullptr;
  long n = BIO_get_mem_data(out.get(), &data);
  return std::string(data, static_cast<size_t>(n));
}

// Whether any <subject_name> of the permissions names `subject`.
bool has_grant_for(const std::string& xml, const std::string& subject) {
  const std::string open = "<subject_name>", close = "</subject_name>";
  for (size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at + 1)) {
    const size_t begin = at + open.size(), end = xml.find(close, begin);
    if (end == std::string::npos) return false;
    if (attributes(xml.substr(begin, end - begin)) == attributes(subject)) return true;
  }
  return false;
}

void check_documents(const SecurityFiles& f) {
  Cert ca = read_certificate("permissions_ca", f.permissions_ca);
  signed_text("governance", f.governance, ca, f.permissions_ca);
  const std::string permissions = signed_text("permissions", f.permissions, ca, f.permissions_ca);
  const std::string subject =
      rfc2253_subject(read_certificate("identity_certificate", f.identity_certificate));
  if (!has_grant_for(permissions, subject))
    refuse("permissions", f.permissions,
           "no grant for " + subject + " (the subject of identity_certificate)");
}

}  // namespace

void check_security_files(const SecurityFiles& files) {
  check_identity(files);
  check_documents(files);
  ERR_clear_error();
}

}  // namespace stepnode::bridge::dds
