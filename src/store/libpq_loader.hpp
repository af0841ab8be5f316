// libpq, loaded when the first PostgreSQL database is opened rather than at
// every start of rvc: linked normally, libpq and what it pulls in (Kerberos,
// LDAP, GnuTLS, SASL: about 20 libraries) cost every `rvc` run about 10 M
// instructions of symbol relocation, several times what `rvc check` spends
// on a small file. libpq-fe.h still gives the declarations and types.
#pragma once

#include <libpq-fe.h>

namespace rvc::store {

// The soname loaded, read from the library at configure time
// (cmake/RuntimeLibraries.cmake, which also lists it for the Docker image).
inline constexpr const char* kLibpqSoname = RVC_LIBPQ_SONAME;

#define RVC_LIBPQ_FUNCTIONS(X)                                                                                 \
  X(PQclear) X(PQconnectdbParams) X(PQconninfoFree) X(PQconninfoParse) X(PQerrorMessage) X(PQexec)           \
  X(PQexecParams) X(PQexecPrepared) X(PQfinish) X(PQfreemem) X(PQgetResult) X(PQgetisnull) X(PQgetlength) X(PQgetvalue)   \
  X(PQnfields) X(PQntuples) X(PQprepare) X(PQputCopyData) X(PQputCopyEnd) X(PQreset) X(PQresultErrorField)  \
  X(PQresultErrorMessage) X(PQresultStatus) X(PQsetNoticeProcessor) X(PQstatus) X(PQtransactionStatus)

struct Libpq {
#define RVC_LIBPQ_POINTER(name) decltype(&::name) name = nullptr;
  RVC_LIBPQ_FUNCTIONS(RVC_LIBPQ_POINTER)
#undef RVC_LIBPQ_POINTER
};

// Loads libpq on first use (thread-safe). Throws DbError naming the library
// and what dlopen said when it is missing or lacks a function.
const Libpq& libpq();

}  // namespace rvc::store
