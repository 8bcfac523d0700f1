#include "server/store/postgres_database.h"

#include <libpq-fe.h>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <cstring>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "server/data_dir.h"

namespace fenestra {
namespace {

// Type oids of the PostgreSQL catalog (pg_type.dat)
constexpr Oid kBoolOid = 16, kByteaOid = 17, kInt8Oid = 20, kInt2Oid = 21, kInt4Oid = 23,
              kTextOid = 25;
// The channel of Notify
constexpr char kChannel[] = "fenestra";
// Seconds a connection attempt may take
constexpr char kConnectTimeoutSeconds[] = "3";

absl::Status Unreachable() {
  return absl::UnavailableError(
      "the server's job store (PostgreSQL) cannot be reached; try again in a few seconds");
}

// `sql` with its `?` numbered as PostgreSQL's $1, $2, ... (outside quoted text).
std::string Number(std::string_view sql) {
  std::string out;
  out.reserve(sql.size() + 16);
  int n = 0;
  char quote = 0;
  for (const char c : sql) {
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '?') {
      absl::StrAppend(&out, "$", ++n);
      continue;
    }
    out.push_back(c);
  }
  return out;
}

int64_t BigEndian(const char* bytes, int length) {
  uint64_t value = 0;
  for (int i = 0; i < length; ++i) value = (value << 8) | static_cast<unsigned char>(bytes[i]);
  // Sign-extend the shorter integers
  if (length < 8 && length > 0 && (static_cast<unsigned char>(bytes[0]) & 0x80)) {
    value |= ~uint64_t{0} << (8 * length);
  }
  return static_cast<int64_t>(value);
}

class PostgresSession final : public SqlSession {
 public:
  explicit PostgresSession(PGconn* conn) : conn_(conn) {}

  using SqlSession::Run;
  absl::StatusOr<SqlResult> Run(std::string_view sql, std::span<const SqlParam> params) override {
    const std::string numbered = Number(sql);
    const size_t n = params.size();
    std::vector<Oid> types(n, 0);
    std::vector<const char*> values(n, nullptr);
    std::vector<int> lengths(n, 0), formats(n, 0);
    std::vector<std::string> integers(n);
    for (size_t i = 0; i < n; ++i) {
      const SqlParam& p = params[i];
      if (const int64_t* value = std::get_if<int64_t>(&p)) {
        std::string& bytes = integers[i];
        for (int b = 7; b >= 0; --b) bytes.push_back(static_cast<char>((*value >> (8 * b)) & 0xff));
        types[i] = kInt8Oid, values[i] = bytes.data(), lengths[i] = 8, formats[i] = 1;
      } else if (const std::string_view* text = std::get_if<std::string_view>(&p)) {
        types[i] = kTextOid, values[i] = text->data(), lengths[i] = static_cast<int>(text->size());
        formats[i] = 1;
      } else if (const SqlBlob* blob = std::get_if<SqlBlob>(&p)) {
        types[i] = kByteaOid, values[i] = blob->bytes.data();
        lengths[i] = static_cast<int>(blob->bytes.size()), formats[i] = 1;
      }
    }
    PGresult* res = PQexecParams(conn_, numbered.c_str(), static_cast<int>(n), types.data(),
                                 values.data(), lengths.data(), formats.data(), /*resultFormat=*/1);
    absl::StatusOr<SqlResult> result = Read(res);
    PQclear(res);
    return result;
  }
  absl::Status Lock(int64_t key) override {
    return Run("SELECT pg_advisory_xact_lock(?)", {key}).status();
  }
  absl::Status Notify() override {
    notified_ = true;
    return Run(absl::StrCat("SELECT pg_notify('", kChannel, "', '')")).status();
  }
  // Runs SQL without parameters.
  absl::Status Exec(const char* sql) { return Run(sql).status(); }

  bool notified() const { return notified_; }
  // The last failure was a deadlock or serialization race: the transaction may run again.
  bool retry() const { return retry_; }

 private:
  absl::StatusOr<SqlResult> Read(PGresult* res) {
    const ExecStatusType status = res ? PQresultStatus(res) : PGRES_FATAL_ERROR;
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) return Failure(res);
    SqlResult result;
    const int rows = PQntuples(res), columns = PQnfields(res);
    result.rows.reserve(rows);
    for (int r = 0; r < rows; ++r) {
      std::vector<SqlRow::Cell> cells(columns);
      for (int c = 0; c < columns; ++c) {
        if (PQgetisnull(res, r, c)) continue;
        const char* value = PQgetvalue(res, r, c);
        const int length = PQgetlength(res, r, c);
        switch (PQftype(res, c)) {
          case kInt8Oid:
          case kInt4Oid:
          case kInt2Oid:
          case kBoolOid:
            cells[c] = BigEndian(value, length);
            break;
          default:
            cells[c] = std::string(value, static_cast<size_t>(length));
        }
      }
      result.rows.emplace_back(std::move(cells));
    }
    // An empty count: a command that changes no rows
    if (!absl::SimpleAtoi(PQcmdTuples(res), &result.changed)) result.changed = 0;
    return result;
  }

  absl::Status Failure(PGresult* res) {
    const char* state = res ? PQresultErrorField(res, PG_DIAG_SQLSTATE) : nullptr;
    const std::string code = state ? state : "";
    const std::string message(
        absl::StripAsciiWhitespace(res ? PQresultErrorMessage(res) : PQerrorMessage(conn_)));
    if (PQstatus(conn_) != CONNECTION_OK || code.starts_with("08") || code == "57P01" ||
        code == "57P02" || code == "57P03") {
      spdlog::debug("PostgreSQL: {}", message);
      return Unreachable();
    }
    retry_ = code == "40001" || code == "40P01";
    if (code == "23505") return absl::AlreadyExistsError("a stored key is taken");
    if (code == "53100") return StorageFullError();
    spdlog::error("PostgreSQL: {} (SQLSTATE {})", message, code);
    return absl::InternalError("the server's job store failed");
  }

  PGconn* conn_;
  bool notified_ = false;
  bool retry_ = false;
};

}  // namespace

std::string RedactPostgresUrl(const std::string& url) {
  const size_t scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const size_t start = scheme + 3;
  const size_t at = url.find('@', start);
  const size_t slash = url.find('/', start);
  if (at == std::string::npos || (slash != std::string::npos && slash < at)) return url;
  const size_t colon = url.find(':', start);
  if (colon == std::string::npos || colon > at) return url;
  return absl::StrCat(url.substr(0, colon + 1), "***", url.substr(at));
}

PostgresDatabase::PostgresDatabase(std::string url)
    : url_(std::move(url)), described_(RedactPostgresUrl(url_)) {}

absl::StatusOr<std::unique_ptr<PostgresDatabase>> PostgresDatabase::Open(const std::string& url,
                                                                         int connections) {
  std::unique_ptr<PostgresDatabase> db(new PostgresDatabase(url));
  absl::Status failure;
  PGconn* first = db->Connect(failure);
  if (!first) {
    return absl::UnavailableError(
        absl::StrCat("cannot connect to the store ", db->described_, ": ", failure.message()));
  }
  db->free_.assign(std::max(1, connections), nullptr);
  db->free_[0] = first;
  db->listener_ = std::thread([raw = db.get()] { raw->Listen(); });
  return db;
}

PostgresDatabase::~PostgresDatabase() {
  stop_ = true;
  if (listener_.joinable()) listener_.join();
  for (PGconn* conn : free_) {
    if (conn) PQfinish(conn);
  }
}

PGconn* PostgresDatabase::Connect(absl::Status& failure) const {
  const char* keywords[] = {"dbname", "connect_timeout", "application_name", nullptr};
  const char* values[] = {url_.c_str(), kConnectTimeoutSeconds, "fenestrad", nullptr};
  PGconn* conn = PQconnectdbParams(keywords, values, /*expand_dbname=*/1);
  if (conn && PQstatus(conn) == CONNECTION_OK) {
    // The server's notices ("already exists, skipping") to the log, not to stderr
    PQsetNoticeProcessor(
        conn,
        [](void*, const char* message) {
          spdlog::debug("PostgreSQL: {}", std::string(absl::StripAsciiWhitespace(message)));
        },
        nullptr);
    return conn;
  }
  const std::string message(
      absl::StripAsciiWhitespace(conn ? PQerrorMessage(conn) : "out of memory"));
  spdlog::debug("PostgreSQL {}: {}", described_, message);
  failure = absl::UnavailableError(message);
  if (conn) PQfinish(conn);
  return nullptr;
}

PGconn* PostgresDatabase::Acquire(absl::Status& failure) {
  PGconn* conn = nullptr;
  {
    std::unique_lock lock(pool_mutex_);
    pool_free_.wait(lock, [&] { return !free_.empty(); });
    conn = free_.back();
    free_.pop_back();
  }
  if (conn) return conn;
  conn = Connect(failure);
  if (!conn) Release(nullptr);
  return conn;
}

void PostgresDatabase::Release(PGconn* conn) {
  {
    std::lock_guard lock(pool_mutex_);
    free_.push_back(conn);
  }
  pool_free_.notify_one();
}

void PostgresDatabase::DropIdle() {
  std::lock_guard lock(pool_mutex_);
  for (PGconn*& conn : free_) {
    if (conn) PQfinish(conn);
    conn = nullptr;
  }
}

void PostgresDatabase::NoteReachable(bool reachable, const absl::Status& failure) {
  if (reachable_.exchange(reachable) == reachable) return;
  if (reachable) {
    spdlog::info("the store {} can be reached again", described_);
  } else {
    spdlog::error(
        "the store {} cannot be reached ({}); requests answer UNAVAILABLE until it is back",
        described_, std::string(failure.message()));
  }
}

absl::Status PostgresDatabase::Transact(const TransactionOptions& options,
                                        const std::function<absl::Status(SqlSession&)>& body) {
  constexpr int kAttempts = 5;
  for (int attempt = 1;; ++attempt) {
    absl::Status failure;
    PGconn* conn = Acquire(failure);
    if (!conn) {
      NoteReachable(false, failure);
      return Unreachable();
    }
    PostgresSession session(conn);
    absl::Status status = session.Exec("BEGIN");
    if (!status.ok() && PQstatus(conn) != CONNECTION_OK && attempt < kAttempts) {
      // A pooled connection the server dropped (it restarted): nothing ran; the idle ones
      // were dropped too, so open another
      PQfinish(conn);
      Release(nullptr);
      DropIdle();
      continue;
    }
    if (status.ok() && !options.durable) {
      status = session.Exec("SET LOCAL synchronous_commit TO off");
    }
    if (status.ok()) status = body(session);
    if (status.ok()) status = session.Exec("COMMIT");
    if (!status.ok() && PQstatus(conn) == CONNECTION_OK &&
        PQtransactionStatus(conn) != PQTRANS_IDLE) {
      (void)session.Exec("ROLLBACK");
    }
    const bool up = PQstatus(conn) == CONNECTION_OK;
    if (!up) PQfinish(conn);
    Release(up ? conn : nullptr);
    NoteReachable(up, status);
    if (!status.ok() && session.retry() && attempt < kAttempts) continue;
    if (status.ok() && session.notified()) Changed();
    return status;
  }
}

void PostgresDatabase::Listen() {
  PGconn* conn = nullptr;
  while (!stop_) {
    if (!conn) {
      absl::Status failure;
      conn = Connect(failure);
      PGresult* res = conn ? PQexec(conn, absl::StrCat("LISTEN ", kChannel).c_str()) : nullptr;
      const bool listening = res && PQresultStatus(res) == PGRES_COMMAND_OK;
      PQclear(res);
      if (!listening) {
        if (conn) PQfinish(conn);
        conn = nullptr;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        continue;
      }
      Changed();  // what happened while no one listened
    }
    pollfd p{PQsocket(conn), POLLIN, 0};
    if (poll(&p, 1, 250) > 0 && PQconsumeInput(conn) == 0) {
      PQfinish(conn);
      conn = nullptr;
      continue;
    }
    bool notified = false;
    while (PGnotify* n = PQnotifies(conn)) {
      notified = true;
      PQfreemem(n);
    }
    if (notified) Changed();
  }
  if (conn) PQfinish(conn);
}

}  // namespace fenestra
