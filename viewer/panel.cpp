#include "panel.hpp"

#include <imgui.h>

#include <algorithm>
#include <cstdio>

#include "core/scene.hpp"
#include "experiments/pipelines.hpp"

namespace deformlab::viewer {
namespace {

Event key(const char* k) {
  Event e;
  e.kind = Event::Kind::key;
  e.key = k;
  return e;
}

Event setting(const std::string& name, const std::string& value) {
  Event e;
  e.kind = Event::Kind::set;
  e.settings[name] = value;
  return e;
}

void pipeline_choice(Session& s, std::vector<Event>& out) {
  if (!ImGui::BeginCombo("pipeline", s.entry().name.c_str())) return;
  for (const PipelineEntry& e : pipelines().all()) {
    std::string why = e.unavailable();
    if (why.empty()) why = e.unsupported(s.integrator());
    ImGui::BeginDisabled(!why.empty());
    if (ImGui::Selectable(e.name.c_str(), &e == &s.entry())) out.push_back(setting("pipeline", e.name));
    ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("%s", why.empty() ? e.summary.c_str() : why.c_str());
  }
  ImGui::EndCombo();
}

void integrator_choice(Session& s, std::vector<Event>& out) {
  if (!ImGui::BeginCombo("integrator", std::string(info(s.integrator()).name).c_str())) return;
  for (const IntegratorInfo& i : integrators()) {
    const std::string why = s.entry().unsupported(i.id);
    ImGui::BeginDisabled(!why.empty());
    if (ImGui::Selectable(std::string(i.name).c_str(), i.id == s.integrator()))
      out.push_back(setting("integrator", std::string(i.name)));
    ImGui::EndDisabled();
    if (!why.empty() && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("%s", why.c_str());
  }
  ImGui::EndCombo();
}

// A text field applied with Enter.
bool text_field(const char* label, std::string& text) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%s", text.c_str());
  const bool enter = ImGui::InputText(label, buf, sizeof buf, ImGuiInputTextFlags_EnterReturnsTrue);
  text = buf;
  return enter;
}

// The step's stages and the frame's draw, each against the longest, on its own clock.
void stage_bars(const Stats& s) {
  double longest = std::max(s.step_ms, s.draw_ms);
  for (const auto& st : s.stages) longest = std::max(longest, st.median_ms);
  auto bar = [&](const std::string& name, double ms, const std::string& what) {
    char label[160];
    std::snprintf(label, sizeof label, "%s %.4f ms", name.c_str(), ms);
    ImGui::ProgressBar(longest > 0 ? float(ms / longest) : 0.f, ImVec2(-1, 0), label);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", what.c_str());
  };
  for (const auto& st : s.stages)
    if (st.name != "step")
      bar(st.name, st.median_ms, "median per step over " + std::to_string(st.steps) + " steps, " + st.clock);
  bar("render", s.draw_ms, "median per frame, " + s.draw_clock);
}

}  // namespace

PanelActions show_panel(PanelState& p, const Stats& s, Session& session, const std::string& message, bool paused,
                        bool recording) {
  PanelActions a;
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - kPanelWidth, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y));
  ImGui::Begin("deformlab", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  const Model& m = session.model();
  ImGui::TextWrapped("%lld nodes, %lld springs", static_cast<long long>(m.node_count()),
                     static_cast<long long>(m.spring_count()));

  pipeline_choice(session, a.events);
  integrator_choice(session, a.events);
  if (p.dt_text.empty()) p.dt_text = std::to_string(session.params().dt);
  if (text_field("dt (s)", p.dt_text)) a.events.push_back(setting("dt", p.dt_text));
  if (!session.entry().options.empty()) {
    std::string names;
    for (const auto& n : session.entry().options) names += (names.empty() ? "" : ", ") + n;
    if (text_field("option", p.option_text)) a.events.push_back(setting("options", p.option_text));
    ImGui::TextDisabled("NAME=VALUE; names: %s", names.c_str());
    for (const auto& [k, v] : session.options()) ImGui::BulletText("%s = %s", k.c_str(), v.c_str());
  }
  ImGui::SliderInt("steps/frame", &p.steps_per_frame, 1, 200);

  if (ImGui::Button(paused ? "run" : "pause")) a.events.push_back(key("space"));
  ImGui::SameLine();
  if (ImGui::Button("step")) a.events.push_back(key("n"));
  ImGui::SameLine();
  if (ImGui::Button("reset")) a.events.push_back(key("backspace"));
  ImGui::SameLine();
  if (ImGui::Button("camera")) a.events.push_back(key("r"));
  bool wire = p.wireframe, points = p.points;
  if (ImGui::Checkbox("wireframe", &wire)) a.events.push_back(key("w"));
  ImGui::SameLine();
  if (ImGui::Checkbox("points", &points)) a.events.push_back(key("m"));
  ImGui::Combo("colour", &p.colour, "plain\0speed (m/s)\0strain\0");
  if (p.colour != 0) {
    ImGui::InputFloat("red at", &p.scale[p.colour], 0.f, 0.f, "%.3g");
    p.scale[p.colour] = std::max(p.scale[p.colour], 1e-6f);
    ImGui::TextDisabled(p.colour == 1 ? "displacement since the last frame over its time"
                                      : "cloth: spans along the grid; mesh: triangle edges");
  }
  if (ImGui::Button("screenshot")) a.events.push_back(key("p"));
  ImGui::SameLine();
  if (ImGui::Button(recording ? "stop recording" : "record")) a.events.push_back(key("v"));

  ImGui::Separator();
  ImGui::Text("t = %.4f s, step %d", session.time(), session.steps());
  if (s.measured) {
    ImGui::TextWrapped("%.0f steps/s, %.1f frames/s (host clock)", s.steps_per_s, s.frames_per_s);
    ImGui::TextWrapped("step %.4f ms (%s)", s.step_ms, s.step_clock.c_str());
    ImGui::TextWrapped("largest displacement %.3g m", s.displacement);
    ImGui::TextWrapped("draw %.3f ms (%s)", s.draw_ms, s.draw_clock.c_str());
    ImGui::TextWrapped("drawn from %s", s.drawn_from.c_str());
  } else {
    ImGui::TextDisabled("timings after the first half second");
  }
  if (ImGui::Checkbox("stage timings", &p.profile)) a.profile_changed = true;
  if (p.profile) stage_bars(s);
  if (!message.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.f, 0.45f, 0.4f, 1.f));
    ImGui::TextWrapped("%s", message.c_str());
    ImGui::PopStyleColor();
  }

  ImGui::Separator();
  ImGui::TextDisabled("left-drag a node: pull it");
  ImGui::TextDisabled("shift-click a node: pin or free it");
  ImGui::TextDisabled("left-drag: orbit, right-drag: pan, wheel: zoom");
  ImGui::TextDisabled("keys: space pause, n step, backspace reset,");
  ImGui::TextDisabled("r camera, w wireframe, m points, c colour,");
  ImGui::TextDisabled("p screenshot, v record / stop");
  ImGui::End();
  return a;
}

}  // namespace deformlab::viewer
