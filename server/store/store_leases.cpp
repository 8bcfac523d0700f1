// Store: work for the replicas' workers, claimed under leases that they renew.
#include <algorithm>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/store/store.h"
#include "server/store/store_internal.h"

namespace fenestra {

// ---- Work

namespace {

using store_internal::kComputing;
using store_internal::kQueued;
using store_internal::kRunning;
using store_internal::NextCounter;
using store_internal::Placeholders;

// Keys of matrices a replica holds that a claim prefers, at most.
constexpr size_t kMaxPreferredKeys = 32;
// Jobs a claim reads in order before it locks the first free one.
constexpr int64_t kClaimCandidates = 16;

// What a claim may take: not `excluded`, jobs whose outdoor key is in `preferred` first.
struct ClaimFilter {
  const std::vector<std::string>& preferred;  // at most kMaxPreferredKeys used
  const std::vector<std::string>& excluded;
};

// The runnable jobs (`jobs`) or site computations in claiming order: `among` null, the
// first few, unlocked; else the first of `among` still runnable, locked (rows other
// transactions hold are skipped). Locking while ordering sorts every row read, so the deep
// queue is ordered without locks. Columns: id, owner, state, lease_owner, the owner's turn,
// 0 for a preferred key, queue_order.
absl::StatusOr<SqlResult> ClaimCandidates(const Database& db, SqlSession& s, bool jobs,
                                          const ClaimFilter& filter,
                                          const std::vector<std::string>* among) {
  const size_t keys = std::min(filter.preferred.size(), kMaxPreferredKeys);
  std::vector<SqlParam> params;
  std::string sql;
  if (jobs) {
    sql = absl::StrCat(
        "SELECT c.id, c.owner, c.state, c.lease_owner, COALESCE(t.last_taken, 0), CASE WHEN "
        "c.outdoor_key IN ",
        keys ? Placeholders(keys) : "(NULL)",
        " THEN 0 ELSE 1 END, c.queue_order FROM jobs c LEFT JOIN turns t ON t.owner = c.owner "
        "WHERE (c.state = ? OR (c.state = ? AND c.lease_expires_unix_ms < {now}))");
    for (size_t i = 0; i < keys; ++i) params.push_back(filter.preferred[i]);
    params.push_back(kQueued);
    params.push_back(kRunning);
  } else {
    sql =
        "SELECT c.id, c.owner, 0, c.lease_owner, COALESCE(t.last_taken, 0), 1, c.queue_order "
        "FROM sites c LEFT JOIN turns t ON t.owner = c.owner WHERE c.state = ? AND "
        "c.lease_expires_unix_ms < {now}";
    params.push_back(kComputing);
  }
  if (!filter.excluded.empty()) {
    absl::StrAppend(&sql, " AND c.id NOT IN ", Placeholders(filter.excluded.size()));
    for (const std::string& id : filter.excluded) params.push_back(id);
  }
  if (among) {
    absl::StrAppend(&sql, " AND c.id IN ", Placeholders(among->size()));
    for (const std::string& id : *among) params.push_back(id);
  }
  absl::StrAppend(&sql, " ORDER BY CASE WHEN c.state = ? THEN 0 ELSE 1 END, 5, 6, 7 LIMIT ?",
                  among ? "{claim_lock}" : "");
  params.push_back(jobs ? kRunning : int64_t{-1});
  params.push_back(among ? int64_t{1} : kClaimCandidates);
  return s.Run(db.Sql(sql), params);
}

// The first runnable job or site computation, locked (none: no row): the first few in
// order, then the first of them no other claim holds (again, a few times, while other
// claims took them all).
absl::StatusOr<SqlResult> FirstRunnable(const Database& db, SqlSession& s, bool jobs,
                                        const ClaimFilter& filter) {
  constexpr int kAttempts = 5;
  for (int attempt = 1;; ++attempt) {
    FENESTRA_ASSIGN_OR_RETURN(first, ClaimCandidates(db, s, jobs, filter, nullptr));
    if (first.rows.empty()) return first;
    std::vector<std::string> ids;
    for (const SqlRow& row : first.rows) ids.push_back(row.Bytes(0));
    FENESTRA_ASSIGN_OR_RETURN(locked, ClaimCandidates(db, s, jobs, filter, &ids));
    if (!locked.rows.empty() || attempt == kAttempts) return locked;
  }
}

}  // namespace

absl::StatusOr<std::optional<Claim>> Store::ClaimWork(const std::string& replica, int64_t lease_ms,
                                                      const std::vector<std::string>& preferred,
                                                      const std::vector<std::string>& excluded,
                                                      std::string* candidate) {
  std::optional<Claim> claim;
  const ClaimFilter filter{preferred, excluded};
  const absl::Status status = Transact([&](SqlSession& s) -> absl::Status {
    claim.reset();
    FENESTRA_ASSIGN_OR_RETURN(job, FirstRunnable(*db_, s, /*jobs=*/true, filter));
    FENESTRA_ASSIGN_OR_RETURN(site, FirstRunnable(*db_, s, /*jobs=*/false, filter));
    // The job or the site: taken-over jobs first, then the user's turn, then the order
    const auto rank = [](const SqlRow& r, bool is_job) {
      return std::tuple(is_job && r.Int(2) == kRunning ? 0 : 1, r.Int(4), r.Int(6));
    };
    bool is_job;
    if (!job.rows.empty() && !site.rows.empty()) {
      is_job = rank(job.rows[0], true) <= rank(site.rows[0], false);
    } else if (!job.rows.empty() || !site.rows.empty()) {
      is_job = !job.rows.empty();
    } else {
      return absl::OkStatus();
    }
    const SqlRow& r = is_job ? job.rows[0] : site.rows[0];
    Claim c;
    c.kind = is_job ? Claim::Kind::kJob : Claim::Kind::kSite;
    c.lease.id = r.Bytes(0);
    c.owner = r.Bytes(1);
    c.taken_over = is_job && r.Int(2) == kRunning;
    c.previous_replica = r.Bytes(3);
    if (candidate) *candidate = c.lease.id;

    FENESTRA_ASSIGN_OR_RETURN(turn, NextCounter(s, "turn"));
    FENESTRA_RETURN_IF_ERROR(
        s.Run("INSERT INTO turns (owner, last_taken) VALUES (?, ?) ON "
              "CONFLICT (owner) DO UPDATE SET last_taken = excluded.last_taken",
              {c.owner, turn})
            .status());
    FENESTRA_ASSIGN_OR_RETURN(
        run, s.Run(Sql(is_job ? "UPDATE jobs SET state = 2, lease_owner = ?, lease_expires_unix_ms "
                                "= {now} + ?, run = run + 1 WHERE id = ? RETURNING run"
                              : "UPDATE sites SET lease_owner = ?, lease_expires_unix_ms = {now} "
                                "+ ?, run = run + 1 WHERE id = ? RETURNING run"),
                   {replica, lease_ms, c.lease.id}));
    c.lease.run = run.rows.at(0).Int(0);
    claim = std::move(c);
    return s.Notify();
  });
  if (!status.ok()) return status;
  return claim;
}

absl::StatusOr<std::vector<Store::Renewal>> Store::RenewLeases(
    int64_t lease_ms, const std::vector<std::pair<Claim::Kind, Lease>>& held) {
  std::vector<Renewal> renewed;
  if (held.empty()) return renewed;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        renewed.assign(held.size(), Renewal{});
        for (size_t i = 0; i < held.size(); ++i) {
          const auto& [kind, lease] = held[i];
          const bool job = kind == Claim::Kind::kJob;
          FENESTRA_ASSIGN_OR_RETURN(
              row, s.Run(Sql(job ? "UPDATE jobs SET lease_expires_unix_ms = {now} + ? WHERE id = "
                                   "? AND run = ? AND state = ? RETURNING cancel_requested"
                                 : "UPDATE sites SET lease_expires_unix_ms = {now} + ? WHERE id "
                                   "= ? AND run = ? AND state = ? RETURNING 0"),
                         {lease_ms, lease.id, lease.run, job ? kRunning : kComputing}));
          renewed[i].held = !row.rows.empty();
          renewed[i].cancel_requested = !row.rows.empty() && row.rows[0].Int(0) != 0;
        }
        return absl::OkStatus();
      },
      /*durable=*/false));
  return renewed;
}

absl::Status Store::ExpireLeases() {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        s.Run("UPDATE jobs SET lease_expires_unix_ms = 0 WHERE state = ?", {kRunning}).status());
    return s.Run("UPDATE sites SET lease_expires_unix_ms = 0 WHERE state = ?", {kComputing})
        .status();
  });
}

absl::Status Store::Release(Claim::Kind kind, const Lease& lease) {
  const bool job = kind == Claim::Kind::kJob;
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        Fenced(s.Run(job ? "UPDATE jobs SET lease_expires_unix_ms = 0 WHERE id = ? AND run = ? "
                           "AND state = ?"
                         : "UPDATE sites SET lease_expires_unix_ms = 0 WHERE id = ? AND run = ? "
                           "AND state = ?",
                     {lease.id, lease.run, job ? kRunning : kComputing}),
               lease));
    return s.Notify();
  });
}

}  // namespace fenestra
