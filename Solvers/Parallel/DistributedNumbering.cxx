#include "DistributedNumbering.h"

#include "Error.h"

#include <algorithm>
#include <climits>
#include <cstring>

namespace translucency
{

namespace
{

std::uint64_t Mix(std::uint64_t x)
{
  // splitmix64's finaliser.
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

struct KeyHash
{
  std::size_t operator()(const PointKey& k) const
  {
    return static_cast<std::size_t>(Mix(k[0] ^ Mix(k[1] ^ Mix(k[2]))));
  }
};

/**
 * An open-addressing (linear probing) index of distinct keys: each slot
 * holds the id of a stored key, `keyOf(id)` returns it. Replaces
 * std::unordered_map in the numbering (one allocation, no node per key:
 * issue 32, the 1-rank numbering's cost was mostly its hash maps).
 */
template <typename KeyOf>
class FlatKeyIndex
{
public:
  FlatKeyIndex(std::size_t expected, KeyOf keyOf)
    : KeyOf_(keyOf)
  {
    std::size_t capacity = 16;
    while (capacity < 2 * expected)
      capacity *= 2;
    Slots_.assign(capacity, -1);
    Mask_ = capacity - 1;
  }

  /// The id stored for `key`, or `id` (stored now, `inserted` set).
  int FindOrInsert(const PointKey& key, int id, bool& inserted)
  {
    std::size_t slot = KeyHash()(key) & Mask_;
    while (true)
    {
      const int stored = Slots_[slot];
      if (stored < 0)
      {
        Slots_[slot] = id;
        inserted = true;
        return id;
      }
      if (KeyOf_(stored) == key)
      {
        inserted = false;
        return stored;
      }
      slot = (slot + 1) & Mask_;
    }
  }

private:
  KeyOf KeyOf_;
  std::vector<int> Slots_;
  std::size_t Mask_ = 0;
};

template <typename KeyOf>
FlatKeyIndex<KeyOf> MakeKeyIndex(std::size_t expected, KeyOf keyOf)
{
  return FlatKeyIndex<KeyOf>(expected, keyOf);
}

int HomeOf(const PointKey& key, int size)
{
  return static_cast<int>(KeyHash()(key) % static_cast<std::size_t>(size));
}

/// All-to-all of typed records: out[r] goes to rank r; returns what every
/// rank sent here, source by source, with counts[r] records from rank r.
template <typename T>
std::vector<T> AllToAll(MPI_Comm comm, const std::vector<std::vector<T>>& out, std::vector<int>& counts)
{
  const int size = static_cast<int>(out.size());
  std::vector<int> sendBytes(size), recvBytes(size), sendOffsets(size + 1, 0),
    recvOffsets(size + 1, 0);
  for (int r = 0; r < size; ++r)
  {
    const std::size_t bytes = out[r].size() * sizeof(T);
    if (bytes > static_cast<std::size_t>(INT_MAX / 2))
    {
      throw Error("distributed solve: a message of more than 1 GB between two ranks (use more ranks)");
    }
    sendBytes[r] = static_cast<int>(bytes);
  }
  MPI_Alltoall(sendBytes.data(), 1, MPI_INT, recvBytes.data(), 1, MPI_INT, comm);
  for (int r = 0; r < size; ++r)
  {
    sendOffsets[r + 1] = sendOffsets[r] + sendBytes[r];
    recvOffsets[r + 1] = recvOffsets[r] + recvBytes[r];
  }
  std::vector<char> send(static_cast<std::size_t>(sendOffsets[size]));
  for (int r = 0; r < size; ++r)
  {
    if (sendBytes[r] > 0)
      std::memcpy(send.data() + sendOffsets[r], out[r].data(), static_cast<std::size_t>(sendBytes[r]));
  }
  std::vector<T> in(static_cast<std::size_t>(recvOffsets[size]) / sizeof(T));
  MPI_Alltoallv(send.data(), sendBytes.data(), sendOffsets.data(), MPI_BYTE, in.data(),
    recvBytes.data(), recvOffsets.data(), MPI_BYTE, comm);
  counts.resize(size);
  for (int r = 0; r < size; ++r)
    counts[r] = recvBytes[r] / static_cast<int>(sizeof(T));
  return in;
}

struct KeyRecord
{
  PointKey Key;
  std::uint64_t Used;
};

} // namespace

PointKey PointKeyFromId(std::int64_t id)
{
  return { static_cast<std::uint64_t>(id), 0, 0 };
}

PointKey PointKeyFromCoordinates(const double* x)
{
  PointKey key;
  for (int d = 0; d < 3; ++d)
  {
    const double v = x[d] + 0.0; // -0 and +0 are one coordinate
    std::memcpy(&key[d], &v, sizeof v);
  }
  return key;
}

void AgreeOnError(MPI_Comm comm, const std::string& localError)
{
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int mine = localError.empty() ? INT_MAX : rank;
  int first = INT_MAX;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == INT_MAX)
  {
    return;
  }
  int length = rank == first ? static_cast<int>(localError.size()) : 0;
  MPI_Bcast(&length, 1, MPI_INT, first, comm);
  std::string message(static_cast<std::size_t>(length), ' ');
  if (rank == first)
    message = localError;
  MPI_Bcast(&message[0], length, MPI_CHAR, first, comm);
  throw Error(size > 1 ? "rank " + std::to_string(first) + ": " + message : message);
}

namespace
{
/// DistributedNumbering::Build: this rank's distinct keys (a piece may
/// repeat a point), each point's distinct key in uniqueOf, and whether any
/// of its points is used.
void DistinctKeys(const std::vector<PointKey>& keys, const std::vector<char>& used,
  std::vector<int>& uniqueOf, std::vector<PointKey>& uniqueKeys, std::vector<char>& uniqueUsed)
{
  const std::size_t n = keys.size();
  uniqueKeys.reserve(n);
  uniqueUsed.reserve(n);
  {
    auto local = MakeKeyIndex(
      n, [&uniqueKeys](int u) -> const PointKey& { return uniqueKeys[static_cast<std::size_t>(u)]; });
    for (std::size_t i = 0; i < n; ++i)
    {
      bool inserted = false;
      const int u = local.FindOrInsert(keys[i], static_cast<int>(uniqueKeys.size()), inserted);
      if (inserted)
      {
        uniqueKeys.push_back(keys[i]);
        uniqueUsed.push_back(0);
      }
      uniqueOf[i] = u;
      uniqueUsed[static_cast<std::size_t>(u)] |= used[i];
    }
  }
}
} // namespace

void DistributedNumbering::Build(
  MPI_Comm comm, const std::vector<PointKey>& keys, const std::vector<char>& used)
{
  MPI_Comm_rank(comm, &Rank_);
  MPI_Comm_size(comm, &Size_);
  const std::size_t n = keys.size();

  // This rank's distinct keys (a piece may repeat a point).
  std::vector<int> uniqueOf(n);
  std::vector<PointKey> uniqueKeys;
  std::vector<char> uniqueUsed;
  DistinctKeys(keys, used, uniqueOf, uniqueKeys, uniqueUsed);

  // Round 1: keys to their homes, which choose the owners (lowest rank using it).
  std::vector<std::vector<KeyRecord>> out(static_cast<std::size_t>(Size_));
  std::vector<std::vector<int>> sent(static_cast<std::size_t>(Size_));
  std::vector<int> homeOf(uniqueKeys.size());
  {
    std::vector<std::size_t> perHome(static_cast<std::size_t>(Size_), 0);
    for (std::size_t u = 0; u < uniqueKeys.size(); ++u)
    {
      homeOf[u] = HomeOf(uniqueKeys[u], Size_);
      ++perHome[static_cast<std::size_t>(homeOf[u])];
    }
    for (int r = 0; r < Size_; ++r)
    {
      out[r].reserve(perHome[r]);
      sent[r].reserve(perHome[r]);
    }
  }
  for (std::size_t u = 0; u < uniqueKeys.size(); ++u)
  {
    const int home = homeOf[u];
    out[home].push_back({ uniqueKeys[u], static_cast<std::uint64_t>(uniqueUsed[u]) });
    sent[home].push_back(static_cast<int>(u));
  }
  std::vector<int> counts;
  std::vector<KeyRecord> in = AllToAll(comm, out, counts);
  out = {};
  std::vector<int> groupOf(in.size()), groupOwner, groupRow, groupFirst;
  {
    // A group's key is that of its first record.
    groupOwner.reserve(in.size());
    groupFirst.reserve(in.size());
    auto groups = MakeKeyIndex(in.size(), [&in, &groupFirst](int g) -> const PointKey& {
      return in[static_cast<std::size_t>(groupFirst[static_cast<std::size_t>(g)])].Key;
    });
    std::size_t e = 0;
    for (int source = 0; source < Size_; ++source)
    {
      for (int k = 0; k < counts[source]; ++k, ++e)
      {
        bool inserted = false;
        const int g =
          groups.FindOrInsert(in[e].Key, static_cast<int>(groupOwner.size()), inserted);
        if (inserted)
        {
          groupOwner.push_back(INT_MAX);
          groupFirst.push_back(static_cast<int>(e));
        }
        groupOf[e] = g;
        if (in[e].Used)
          groupOwner[g] = std::min(groupOwner[g], source);
      }
    }
  }
  groupFirst = {};
  in = {};
  std::vector<std::vector<int>> reply(static_cast<std::size_t>(Size_));
  for (int source = 0; source < Size_; ++source)
    reply[source].reserve(static_cast<std::size_t>(counts[source]));
  {
    std::size_t e = 0;
    for (int source = 0; source < Size_; ++source)
      for (int k = 0; k < counts[source]; ++k, ++e)
        reply[source].push_back(groupOwner[groupOf[e]] == INT_MAX ? -1 : groupOwner[groupOf[e]]);
  }
  std::vector<int> replyCounts;
  std::vector<int> owners = AllToAll(comm, reply, replyCounts);
  std::vector<int> uniqueOwner(uniqueKeys.size(), -1);
  {
    std::size_t e = 0;
    for (int home = 0; home < Size_; ++home)
      for (int u : sent[home])
        uniqueOwner[static_cast<std::size_t>(u)] = owners[e++];
  }

  // Rows: owners number their vertices in order, ranks one after the other.
  long long owned = 0;
  for (int o : uniqueOwner)
    owned += o == Rank_ ? 1 : 0;
  long long begin = 0, total = 0;
  MPI_Exscan(&owned, &begin, 1, MPI_LONG_LONG, MPI_SUM, comm);
  if (Rank_ == 0)
    begin = 0;
  MPI_Allreduce(&owned, &total, 1, MPI_LONG_LONG, MPI_SUM, comm);
  if (total > INT_MAX)
  {
    throw Error("distributed solve: more than 2^31 - 1 vertices (hypre is built with 32-bit ids)");
  }
  RowBegin_ = static_cast<int>(begin);
  RowEnd_ = static_cast<int>(begin + owned);
  Rows_ = total;
  std::vector<int> uniqueRow(uniqueKeys.size(), -1);
  int next = RowBegin_;
  for (std::size_t u = 0; u < uniqueKeys.size(); ++u)
    if (uniqueOwner[u] == Rank_)
      uniqueRow[u] = next++;

  // Round 2: the owners tell the homes their rows; the homes tell everyone.
  std::vector<std::vector<int>> rowsOut(static_cast<std::size_t>(Size_));
  for (int home = 0; home < Size_; ++home)
    for (int u : sent[home])
      rowsOut[home].push_back(uniqueRow[static_cast<std::size_t>(u)]);
  std::vector<int> rowsIn = AllToAll(comm, rowsOut, counts);
  rowsOut = {};
  groupRow.assign(groupOwner.size(), -1);
  for (std::size_t e = 0; e < rowsIn.size(); ++e)
    if (rowsIn[e] >= 0)
      groupRow[groupOf[e]] = rowsIn[e];
  for (auto& r : reply)
    r.clear();
  {
    std::size_t e = 0;
    for (int source = 0; source < Size_; ++source)
      for (int k = 0; k < counts[source]; ++k, ++e)
        reply[source].push_back(groupRow[groupOf[e]]);
  }
  std::vector<int> rows = AllToAll(comm, reply, replyCounts);
  {
    std::size_t e = 0;
    for (int home = 0; home < Size_; ++home)
      for (int u : sent[home])
        uniqueRow[static_cast<std::size_t>(u)] = rows[e++];
  }
  Row_.resize(n);
  Owner_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t u = static_cast<std::size_t>(uniqueOf[i]);
    Row_[i] = uniqueRow[u];
    Owner_[i] = uniqueRow[u] < 0 ? -1 : uniqueOwner[u];
  }
}

std::vector<double> DistributedNumbering::SumToOwners(
  MPI_Comm comm, const std::vector<double>& values, int components) const
{
  const std::size_t k = static_cast<std::size_t>(components);
  std::vector<double> result(static_cast<std::size_t>(GetNumberOfOwnedRows()) * k, 0.0);
  std::vector<std::vector<double>> out(static_cast<std::size_t>(Size_));
  for (std::size_t i = 0; i < Row_.size(); ++i)
  {
    if (Row_[i] < 0)
      continue;
    const double* v = values.data() + k * i;
    if (Owner_[i] == Rank_)
    {
      double* r = result.data() + k * static_cast<std::size_t>(Row_[i] - RowBegin_);
      for (std::size_t c = 0; c < k; ++c)
        r[c] += v[c];
    }
    else
    {
      auto& o = out[static_cast<std::size_t>(Owner_[i])];
      o.push_back(static_cast<double>(Row_[i]));
      o.insert(o.end(), v, v + k);
    }
  }
  std::vector<int> counts;
  const std::vector<double> in = AllToAll(comm, out, counts);
  for (std::size_t e = 0; e < in.size(); e += k + 1)
  {
    double* r = result.data() + k * static_cast<std::size_t>(static_cast<int>(in[e]) - RowBegin_);
    for (std::size_t c = 0; c < k; ++c)
      r[c] += in[e + 1 + c];
  }
  return result;
}

std::vector<double> DistributedNumbering::FetchFromOwners(
  MPI_Comm comm, const std::vector<double>& owned, int components) const
{
  const std::size_t k = static_cast<std::size_t>(components);
  std::vector<double> result(Row_.size() * k, 0.0);
  std::vector<std::vector<int>> requests(static_cast<std::size_t>(Size_));
  std::vector<std::vector<int>> asked(static_cast<std::size_t>(Size_));
  for (std::size_t i = 0; i < Row_.size(); ++i)
  {
    if (Row_[i] < 0)
      continue;
    if (Owner_[i] == Rank_)
    {
      const double* v = owned.data() + k * static_cast<std::size_t>(Row_[i] - RowBegin_);
      std::copy(v, v + k, result.data() + k * i);
    }
    else
    {
      requests[static_cast<std::size_t>(Owner_[i])].push_back(Row_[i]);
      asked[static_cast<std::size_t>(Owner_[i])].push_back(static_cast<int>(i));
    }
  }
  std::vector<int> counts;
  const std::vector<int> in = AllToAll(comm, requests, counts);
  std::vector<std::vector<double>> answers(static_cast<std::size_t>(Size_));
  {
    std::size_t e = 0;
    for (int source = 0; source < Size_; ++source)
      for (int j = 0; j < counts[source]; ++j, ++e)
      {
        const double* v = owned.data() + k * static_cast<std::size_t>(in[e] - RowBegin_);
        answers[source].insert(answers[source].end(), v, v + k);
      }
  }
  const std::vector<double> values = AllToAll(comm, answers, counts);
  std::size_t e = 0;
  for (int owner = 0; owner < Size_; ++owner)
    for (int i : asked[owner])
    {
      std::copy(values.data() + e, values.data() + e + k, result.data() + k * static_cast<std::size_t>(i));
      e += k;
    }
  return result;
}

std::size_t DistributedNumbering::GetMemoryBytes() const
{
  return (Row_.capacity() + Owner_.capacity()) * sizeof(int);
}

std::vector<int> CountSharedTriangles(MPI_Comm comm, const std::vector<int>& triangleRows)
{
  int size = 1;
  MPI_Comm_size(comm, &size);
  const std::size_t n = triangleRows.size() / 3;
  std::vector<std::vector<PointKey>> out(static_cast<std::size_t>(size));
  std::vector<std::vector<int>> sent(static_cast<std::size_t>(size));
  for (std::size_t f = 0; f < n; ++f)
  {
    int v[3] = { triangleRows[3 * f], triangleRows[3 * f + 1], triangleRows[3 * f + 2] };
    std::sort(v, v + 3);
    const PointKey key = { static_cast<std::uint64_t>(v[0]), static_cast<std::uint64_t>(v[1]),
      static_cast<std::uint64_t>(v[2]) };
    const int home = HomeOf(key, size);
    out[home].push_back(key);
    sent[home].push_back(static_cast<int>(f));
  }
  std::vector<int> counts;
  const std::vector<PointKey> in = AllToAll(comm, out, counts);
  out = {};
  // Per distinct key (its first record's index) how many records have it.
  std::vector<int> groupOf(in.size()), groupCount, groupFirst;
  {
    auto seen = MakeKeyIndex(in.size(), [&in, &groupFirst](int g) -> const PointKey& {
      return in[static_cast<std::size_t>(groupFirst[static_cast<std::size_t>(g)])];
    });
    for (std::size_t e = 0; e < in.size(); ++e)
    {
      bool inserted = false;
      const int g = seen.FindOrInsert(in[e], static_cast<int>(groupCount.size()), inserted);
      if (inserted)
      {
        groupCount.push_back(0);
        groupFirst.push_back(static_cast<int>(e));
      }
      groupOf[e] = g;
      ++groupCount[static_cast<std::size_t>(g)];
    }
  }
  std::vector<std::vector<int>> reply(static_cast<std::size_t>(size));
  {
    std::size_t e = 0;
    for (int source = 0; source < size; ++source)
    {
      reply[source].reserve(static_cast<std::size_t>(counts[source]));
      for (int j = 0; j < counts[source]; ++j, ++e)
        reply[source].push_back(groupCount[static_cast<std::size_t>(groupOf[e])]);
    }
  }
  const std::vector<int> answers = AllToAll(comm, reply, counts);
  std::vector<int> result(n, 0);
  std::size_t e = 0;
  for (int home = 0; home < size; ++home)
    for (int f : sent[home])
      result[static_cast<std::size_t>(f)] = answers[e++];
  return result;
}

} // namespace translucency
