#include "PowerReport.h"

#include "vtkSolveDiffusion.h"

#include <iomanip>

namespace translucency_app
{

nlohmann::json PowerBalanceJson(vtkSolveDiffusion* solve)
{
  if (solve->GetModulationFrequency() > 0.0)
  {
    return nullptr; // complex fluence: no steady-state balance
  }
  double injected[3], absorbed[3], escaped[3];
  if (!solve->ComputePowerBalance(injected, absorbed, escaped))
  {
    return nullptr;
  }
  static const char* channel[3] = { "R", "G", "B" };
  nlohmann::json balance;
  for (int c = 0; c < 3; ++c)
  {
    const double imbalance =
      injected[c] > 0.0 ? (absorbed[c] + escaped[c] - injected[c]) / injected[c] : 0.0;
    balance[channel[c]] = { { "injected", injected[c] }, { "absorbed", absorbed[c] },
      { "escaped", escaped[c] }, { "imbalance", imbalance } };
  }
  return balance;
}

void PrintPowerBalance(const nlohmann::json& balance, std::ostream& out)
{
  if (balance.is_null())
  {
    return;
  }
  out << "power (W)     injected     absorbed      escaped  (absorbed+escaped-injected)/injected\n";
  for (const char* c : { "R", "G", "B" })
  {
    const nlohmann::json& b = balance[c];
    out << "  channel " << c << std::scientific << std::setprecision(4) << std::setw(13)
        << b["injected"].get<double>() << std::setw(13) << b["absorbed"].get<double>()
        << std::setw(13) << b["escaped"].get<double>() << std::setprecision(2) << std::setw(12)
        << b["imbalance"].get<double>() << std::defaultfloat << "\n";
  }
}

} // namespace translucency_app
