/**
 * @file TranslucencyColourSettings.h
 * @brief How ParaView colours the plugin's arrays by default: a named
 * component, with the unit in the colour-bar title.
 *
 * Called once when the plugin loads (paraview_add_plugin INITIALIZERS). It
 * adds, at the lowest priority (a user's or a site's settings win), the
 * settings ParaView reads when it makes the colour map of an array by name
 * (vtkSMSettings "array_lookup_tables.<array>"): the colour-bar title with
 * the unit, and for the three-channel arrays (Fluence, Irradiance, Radiance,
 * the coefficients) the component G instead of the magnitude (the magnitude
 * of an (R, G, B) triple is no physical quantity; G is the channel nearest
 * the eye's luminance peak).
 */
#ifndef TranslucencyColourSettings_h
#define TranslucencyColourSettings_h

#include <string>

/// The settings as JSON (what TranslucencyRegisterColourSettings adds).
std::string TranslucencyColourSettingsJson();

/// Adds TranslucencyColourSettingsJson() to vtkSMSettings at priority 0.
void TranslucencyRegisterColourSettings();

#endif
