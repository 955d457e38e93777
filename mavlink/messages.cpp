#include "mavlink/messages.hpp"

#include <algorithm>
#include <cstring>

namespace alight::mavlink {

namespace {

template <class M>
constexpr MessageInfo info_of() {
  return {M::kId, M::kName, M::kCrcExtra, M::kBaseLength, M::kMaxLength};
}

template <class... Ms>
constexpr auto make_infos(MessageList<Ms...>) {
  return std::array<MessageInfo, sizeof...(Ms)>{info_of<Ms>()...};
}

constexpr auto kInfos = make_infos(KnownMessages{});

}  // namespace

const MessageInfo* find_message(uint32_t msgid) {
  for (const MessageInfo& info : kInfos)
    if (info.id == msgid) return &info;
  return nullptr;
}

std::string statustext_string(const Statustext& m) {
  const auto end = std::find(m.text.begin(), m.text.end(), '\0');
  return std::string(m.text.begin(), end);
}

void set_statustext(Statustext& m, std::string_view text) {
  m.text.fill('\0');
  std::memcpy(m.text.data(), text.data(), std::min(text.size(), m.text.size()));
}

std::string param_id_string(const std::array<char, 16>& id) {
  const auto end = std::find(id.begin(), id.end(), '\0');
  return std::string(id.begin(), end);
}

void set_param_id(std::array<char, 16>& id, std::string_view name) {
  id.fill('\0');
  std::memcpy(id.data(), name.data(), std::min(name.size(), id.size()));
}

}  // namespace alight::mavlink
