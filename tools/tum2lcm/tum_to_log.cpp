#include "tum_to_log.hpp"

#include <lcm/lcm-cpp.hpp>

#include "libcvo/auth/authenticator.hpp"
#include "libcvo/auth/sender.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"

namespace cvo::tools {

LogSummary tum_to_log(const std::filesystem::path& tum_dir, const std::filesystem::path& log,
                      const TumToLogOptions& options) {
  io::TumOptions tum_options;
  tum_options.max_frames = options.max_frames;
  auto sequence = io::TumSequence::open(tum_dir, tum_options);

  auth::Signer signer(options.keys, auth::this_process_sender_id("tum2lcm"));
  LogSummary summary;
  {
    ::lcm::LogFile out(log.string(), "w");
    if (!out.good()) throw io::InputError(log, "cannot create the log file");
    while (auto frame = sequence.next()) {
      std::string error;
      const auto message = lcm::to_message(*frame, options.encoding, &error);
      if (!message) throw io::InputError(sequence.files()[frame->index].rgb, error);
      auto bytes = lcm::encode(*message);
      signer.sign(options.channel, bytes);
      ::lcm::LogEvent event{};
      event.eventnum = static_cast<std::int64_t>(summary.frames);  // LogFile numbers events itself
      event.timestamp = message->utime;
      event.channel = options.channel;
      event.datalen = static_cast<std::int32_t>(bytes.size());
      event.data = bytes.data();
      if (out.writeEvent(&event) != 0) throw io::InputError(log, "write failed (disk full?)");
      ++summary.frames;
    }
  }  // closes (and flushes) the log before its size is read
  summary.bytes = std::filesystem::file_size(log);
  return summary;
}

}  // namespace cvo::tools
