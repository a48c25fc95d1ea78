// The mass-function table of a friends-of-friends catalogue (docs/groups.md, "Mass function").
#include "app/MassFunctionCommand.hpp"

#include <fmt/format.h>

#include "app/TextFile.hpp"
#include "core/Error.hpp"
#include "cosmology/Background.hpp"
#include "cosmology/PowerSpectrum.hpp"
#include "groups/MassFunction.hpp"
#include "io/GroupFiles.hpp"

namespace fountain {

std::string write_mass_function(const MassFunctionRequest& request) {
  const io::FofHalos halos = io::read_fof_halos(request.catalogue);
  if (!(halos.omega_m > 0.0) || !(halos.time > 0.0))
    throw InputError(fmt::format("{}: not a cosmological catalogue (its /Header lacks a positive Omega0 or Time)",
                                 request.catalogue));
  if (!(request.log_max > request.log_min) || !(request.width > 0.0))
    throw InputError(fmt::format("mass bins: --log-max ({}) must exceed --log-min ({}) and --bin-width ({}) be positive",
                                 request.log_max, request.log_min, request.width));
  const double omega_b = request.omega_b >= 0.0 ? request.omega_b : halos.omega_b >= 0.0 ? halos.omega_b : 0.04;
  if (omega_b >= halos.omega_m)
    throw InputError(fmt::format("Omega_b = {} must be below the catalogue's Omega0 = {}", omega_b, halos.omega_m));
  const cosmology::CosmologyParams c{halos.omega_m, halos.omega_lambda, omega_b, halos.hubble_param};
  const cosmology::TransferKind kind = cosmology::transfer_kind_named(request.transfer);
  // The model works in Msun/h and Mpc/h; the catalogue in its snapshot's units.
  const Units reference;
  const double to_msun_h = halos.units.mass_cgs / reference.mass_cgs;
  const double to_mpc_h = halos.units.length_cgs / reference.length_cgs;
  const cosmology::Background background(c);
  const double growth = background.growth(halos.time) / background.growth(1.0);
  const groups::MassFunctionModel model(
      cosmology::LinearPowerSpectrum(cosmology::EisensteinHu(c, kind), request.n_s, request.sigma_8),
      halos.omega_m * cosmology::critical_density0_in(reference), growth);
  std::vector<double> masses(halos.mass.size());
  for (std::size_t g = 0; g < masses.size(); ++g) masses[g] = halos.mass[g] * to_msun_h;
  const double box = halos.box * to_mpc_h;
  const auto bins = groups::bin_mass_function(masses, box * box * box, model, request.log_min, request.log_max, request.width);

  std::string text = fmt::format(
      "# halo mass function of {} (box {} Mpc/h, a = {}, Omega_m {}, Omega_b {}, h {}, sigma_8 {}, n_s {}, {} "
      "transfer)\n# expected counts: the box volume times dn/dln M integrated over each bin; Jenkins et al. (2001) "
      "is nan where its fit does not reach the whole bin\n# log10_M_lo log10_M_hi count jenkins sheth_tormen\n",
      request.catalogue, box, halos.time, halos.omega_m, omega_b, halos.hubble_param, request.sigma_8, request.n_s,
      request.transfer);
  std::size_t counted = 0;
  for (const auto& b : bins) {
    text += fmt::format("{:.4f} {:.4f} {} {:.6g} {:.6g}\n", b.log_lo, b.log_hi, b.count, b.jenkins, b.sheth_tormen);
    counted += b.count;
  }
  write_text_file(request.output, text);
  return fmt::format("wrote {} ({} of {} groups in {} bins from 10^{} to 10^{} Msun/h)", request.output, counted,
                     masses.size(), bins.size(), request.log_min, request.log_max);
}

}  // namespace fountain
