#include "metro_json.h"

namespace octolod::cli {

nlohmann::json deviation_json(const measure::Deviation& d) {
  nlohmann::json j = {{"samples", d.samples},
                      {"mean", d.mean},
                      {"rms", d.rms},
                      {"max", d.max},
                      {"mean_relative", d.mean_relative},
                      {"rms_relative", d.rms_relative},
                      {"max_relative", d.max_relative},
                      {"max_at", d.max_at},
                      {"max_closest", d.max_closest}};
  if (d.compared.normal) {
    j["normal_mean_degrees"] = d.normal_mean_degrees;
    j["normal_max_degrees"] = d.normal_max_degrees;
  }
  if (d.compared.color) j["color_rms"] = d.color_rms;
  if (d.compared.uv) j["uv_rms"] = d.uv_rms;
  return j;
}

nlohmann::json metro_json(const measure::MetroReport& r) {
  return {{"diagonal", r.diagonal},
          {"area_a", r.area_a},
          {"area_b", r.area_b},
          {"a_to_b", deviation_json(r.a_to_b)},
          {"b_to_a", deviation_json(r.b_to_a)},
          {"two_sided", deviation_json(r.two_sided)},
          {"threads", r.threads},
          {"seconds", r.seconds}};
}

void place_maxima(measure::MetroReport& report, const std::array<double, 3>& origin) {
  for (measure::Deviation* d : {&report.a_to_b, &report.b_to_a, &report.two_sided})
    for (std::size_t k = 0; k < 3; ++k) {
      d->max_at[k] += origin[k];
      d->max_closest[k] += origin[k];
    }
}

}  // namespace octolod::cli
