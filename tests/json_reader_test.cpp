// read_json against nlohmann's own sax_parse: the same events for every text both accept, the
// same verdict for every text, and the same events whatever the chunk size of a stream.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "json_reader.h"

namespace octolod {
namespace {

using nlohmann::json;

// Every event as a line; a syntax error ends the list.
class Recorder : public nlohmann::json_sax<json> {
 public:
  std::vector<std::string> events;

  bool null() override { return add("null"); }
  bool boolean(bool value) override { return add(value ? "true" : "false"); }
  bool number_integer(number_integer_t value) override { return add("integer " + std::to_string(value)); }
  bool number_unsigned(number_unsigned_t value) override { return add("unsigned " + std::to_string(value)); }
  bool number_float(number_float_t value, const string_t& text) override {
    char bits[32];
    std::snprintf(bits, sizeof bits, "%a", value);
    return add("float " + std::string(bits) + " " + text);
  }
  bool string(string_t& value) override { return add("string " + value); }
  bool binary(binary_t& /*value*/) override { return add("binary"); }
  bool start_object(std::size_t elements) override { return add("{ " + std::to_string(elements)); }
  bool key(string_t& value) override { return add("key " + value); }
  bool end_object() override { return add("}"); }
  bool start_array(std::size_t elements) override { return add("[ " + std::to_string(elements)); }
  bool end_array() override { return add("]"); }
  bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                   const nlohmann::detail::exception& /*error*/) override {
    add("error");
    return false;  // (true would tell nlohmann to go on as if the text were valid)
  }

 private:
  bool add(std::string line) {
    events.push_back(std::move(line));
    return true;
  }
};

struct Outcome {
  bool accepted;
  std::vector<std::string> events;  // only compared when accepted
};

Outcome nlohmann_reads(const std::string& text) {
  Recorder recorder;
  const bool accepted = json::sax_parse(text, &recorder);
  return {accepted, recorder.events};
}

Outcome ours_from_memory(const std::string& text, std::string* error = nullptr) {
  Recorder recorder;
  const JsonReadResult result = read_json(text, recorder);
  if (error) *error = result.error;
  return {result.error.empty(), recorder.events};
}

Outcome ours_from_stream(const std::string& text, std::size_t chunk) {
  std::istringstream in(text);
  Recorder recorder;
  const JsonReadResult result = read_json(in, recorder, chunk);
  return {result.error.empty(), recorder.events};
}

void expect_like_nlohmann(const std::string& text) {
  const Outcome theirs = nlohmann_reads(text);
  std::string error;
  const Outcome ours = ours_from_memory(text, &error);
  ASSERT_EQ(ours.accepted, theirs.accepted) << "text: " << text << "\nour error: " << error;
  if (!ours.accepted) {
    EXPECT_NE(error.find("syntax error at line "), std::string::npos) << error;
    return;
  }
  EXPECT_EQ(ours.events, theirs.events) << text;
  for (std::size_t chunk : {1, 2, 3, 7, 64}) {
    const Outcome streamed = ours_from_stream(text, chunk);
    EXPECT_TRUE(streamed.accepted) << "chunk " << chunk << ": " << text;
    EXPECT_EQ(streamed.events, theirs.events) << "chunk " << chunk << ": " << text;
  }
}

TEST(JsonReader, ReadsValidTextsAsNlohmannDoes) {
  const std::vector<std::string> texts = {
      "{}", "[]", " true ", "null", "false", "\"\"", "0", "-0", "17", "-17", "\xEF\xBB\xBF{}",
      R"({"a":[1,-2,3.5,1e3,-0.0,0.0,1E-2,2.5e+7,18446744073709551615,18446744073709551616,
              -9223372036854775808,-9223372036854775809,123456789012345678901234567890]})",
      R"(["\u00e9\ud83d\ude00\n\t\\\"\/\b\f\r", "\u0000", "caf\u00C9"])",
      "[\"\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80\xEF\xBF\xBD\"]",  // raw UTF-8 of 2, 3 and 4 bytes
      "[1e-400, -1e-400, 5e-324, 1.7976931348623157e308, 0.1, 3.141592653589793238462643383279]",
      "{\n  \"a\": {\"b\": {\"c\": [{}, [], [[]], {\"d\": null}]}},\n  \"a\": 2\n}",
      "\t\r\n [ 1 , 2 ] \n",
  };
  for (const std::string& text : texts) expect_like_nlohmann(text);
  std::string deep;
  for (int i = 0; i < 10000; ++i) deep += "[{\"k\":";
  deep += "0";
  for (int i = 0; i < 10000; ++i) deep += "}]";
  expect_like_nlohmann(deep);
}

TEST(JsonReader, RejectsWhatNlohmannRejects) {
  const std::vector<std::string> texts = {
      "", " ", "{", "[", "]", "}", "[1,]", "{\"a\":1,}", "{\"a\" 1}", "{1:2}", "{\"a\":}", "[1 2]", "{} {}",
      "01", "1.", ".5", "+1", "-", "1e", "1e+", "-a", "0x10", "1e400", "-1e400", "tru", "nul", "falsy", "True",
      "\"abc", "\"\\x\"", "\"\\u12\"", "\"\\u12g4\"", "\"\\ud800\"", "\"\\udc00\"", "\"\\ud800\\u0041\"",
      "\"\\ud800x\"", "\"a\nb\"", "\"a\tb\"", "\"\xC0\x80\"", "\"\xC3\"", "\"\xED\xA0\x80\"",
      "\"\xF4\x90\x80\x80\"", "\"\xF5\x80\x80\x80\"", "\"\x80\"", "\"\xE2\x82\"", "\xEF\xBB", "\xEF\xBB\xBF",
      "[\"a\" \"b\"]", "{\"a\":1 \"b\":2}",
  };
  for (const std::string& text : texts) expect_like_nlohmann(text);
}

TEST(JsonReader, SaysWhereTheTextIsWrong) {
  std::string error;
  EXPECT_FALSE(ours_from_memory("{\n  \"a\": 1,\n  \"b\": tru\n}", &error).accepted);
  EXPECT_NE(error.find("line 3, column 11 (byte 22)"), std::string::npos) << error;
  EXPECT_NE(error.find("invalid literal"), std::string::npos) << error;
  EXPECT_FALSE(ours_from_memory("[1, 2", &error).accepted);
  EXPECT_NE(error.find("line 1, column 6 (byte 5)"), std::string::npos) << error;
  EXPECT_NE(error.find("the end of the text"), std::string::npos) << error;
}

TEST(JsonReader, StopsWhereTheHandlerSays) {
  struct StopAtSecondKey : Recorder {
    int keys = 0;
    bool key(string_t& value) override {
      Recorder::key(value);
      return ++keys < 2;
    }
  } handler;
  const JsonReadResult result = read_json(R"({"a": 1, "b": 2, "c": 3})", handler);
  EXPECT_TRUE(result.stopped);
  EXPECT_TRUE(result.error.empty());
  EXPECT_EQ(handler.events, (std::vector<std::string>{"{ 18446744073709551615", "key a", "unsigned 1", "key b"}));
}

// Texts near valid ones: a dumped document with bytes changed, dropped, doubled or cut off.
TEST(JsonReader, AgreesWithNlohmannOnMutatedDocuments) {
  json doc = {{"format", "octolod-manifest"},
              {"values", {1, -2, 3.25, 1e-7, 12345678901234567890ull, true, false, nullptr}},
              {"nested", {{"a", json::array()}, {"b", json::object()}, {"c", "x\"y\\z\u00e9"}}}};
  const std::string base = doc.dump(1);
  const std::string alphabet = "{}[],:\"\\/0123456789.eE+-tfnurlasbx \n\t\xC3\xA9\x80\xFF";
  std::mt19937 random(20261203);
  int accepted = 0;
  for (int round = 0; round < 3000; ++round) {
    std::string text = base;
    const int edits = 1 + static_cast<int>(random() % 3);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = random() % text.size();
      switch (random() % 4) {
        case 0: text[at] = alphabet[random() % alphabet.size()]; break;
        case 1: text.erase(at, 1); break;
        case 2: text.insert(at, 1, text[at]); break;
        case 3: text.resize(at); break;
      }
    }
    expect_like_nlohmann(text);
    if (HasFatalFailure()) return;
    accepted += nlohmann_reads(text).accepted;
  }
  EXPECT_GT(accepted, 100);  // the comparison covered accepted texts too
}

}  // namespace
}  // namespace octolod
