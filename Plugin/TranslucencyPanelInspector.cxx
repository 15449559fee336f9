/**
 * @file TranslucencyPanelInspector.cxx
 * @brief What the Properties panel shows of a proxy's tables, for the GUI test
 * (Testing/Python/ParaViewGuiChain.py) and the documentation's screenshot.
 *
 * The GUI's Python has no Qt binding, so the test calls this C function of
 * the plugin with ctypes. It turns on the panel's advanced properties (the
 * gear button of every pqSearchBox: the tables are advanced properties, and
 * `paraview --dr` ignores the settings that would show them), finds the
 * property widgets of the named properties of the proxy `proxyXmlName`,
 * reports for each whether it is visible, the panel's label next to it and
 * the column headers of its table, and saves one picture of the tables
 * with their labels.
 */

#include "pqPropertyWidget.h"
#include "pqProxyWidget.h"

#include <QApplication>
#include <QPoint>
#include <QRegularExpression>
#include <QHeaderView>
#include <QLabel>
#include <QPainter>
#include <QPalette>
#include <QPixmap>
#include <QRect>
#include <QTableView>
#include <QVariant>
#include <QWidget>

#include <vtkSMProperty.h>
#include <vtkSMProxy.h>

#include <cstdlib>
#include <algorithm>
#include <sstream>
#include <utility>
#include <string>
#include <vector>

namespace
{

std::string Quote(const QString& text)
{
  std::string out = "\"";
  for (const char c : text.toStdString())
  {
    if (c == '"' || c == '\\')
    {
      out += '\\';
    }
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

/// A label's text without its rich-text tags (pqProxyWidget writes
/// "<p>Point Sources</p>").
QString PlainText(const QString& text)
{
  QString plain = text;
  plain.remove(QRegularExpression("<[^>]*>"));
  return plain.simplified();
}

/// The visible QLabel of the panel (the pqProxyWidget holding `widget`)
/// that shows `text`, nearest to `widget` vertically (pqProxyWidget lays a
/// property's label out next to its widget).
QLabel* LabelOf(pqPropertyWidget* widget, const QString& text)
{
  QWidget* panel = widget;
  while (panel && !qobject_cast<pqProxyWidget*>(panel))
  {
    panel = panel->parentWidget();
  }
  if (!panel)
  {
    return nullptr;
  }
  const int y = widget->mapTo(panel, QPoint(0, widget->height() / 2)).y();
  QLabel* nearest = nullptr;
  int distance = 0;
  for (QLabel* label : panel->findChildren<QLabel*>())
  {
    if (label->isVisible() && PlainText(label->text()) == text.simplified())
    {
      const int d = std::abs(label->mapTo(panel, QPoint(0, label->height() / 2)).y() - y);
      if (!nearest || d < distance)
      {
        nearest = label;
        distance = d;
      }
    }
  }
  return nearest;
}

} // namespace

/**
 * Shows the advanced properties, then describes the tables of `names` (a
 * comma-separated list of XML property names) of the visible panel of the
 * proxy `proxyXmlName` as JSON:
 * {"advanced_boxes": n, "tables": [{"property": .., "visible": .., "label":
 * .. or null, "headers": [..], "header_visible": ..}, ...], "picture": ..}.
 * The picture (PNG at `pngPath`, if not empty) spans the found widgets and
 * their labels, each rendered by its widget and stacked as the panel lays
 * them out. The returned text lives until the next call.
 */
extern "C" __attribute__((visibility("default"))) const char* TranslucencyInspectPanelTables(
  const char* proxyXmlName, const char* names, const char* pngPath)
{
  static std::string result;
  // The gear button of the panel's search box (a user's click), then every
  // proxy widget filtered with the advanced properties shown (the panel
  // applies the button's state when it next updates; this does it now).
  int boxes = 0;
  for (QWidget* widget : QApplication::allWidgets())
  {
    if (widget->inherits("pqSearchBox") && widget->property("advancedSearchEnabled").toBool())
    {
      widget->setProperty("advancedSearchActive", true);
      ++boxes;
    }
  }
  for (int k = 0; k < 3; ++k)
  {
    QApplication::processEvents();
  }
  for (QWidget* widget : QApplication::allWidgets())
  {
    if (auto* proxyWidget = qobject_cast<pqProxyWidget*>(widget))
    {
      proxyWidget->filterWidgets(true);
    }
  }
  for (int k = 0; k < 3; ++k)
  {
    QApplication::processEvents();
  }

  std::vector<std::string> wanted;
  std::stringstream list(names ? names : "");
  for (std::string name; std::getline(list, name, ',');)
  {
    wanted.push_back(name);
  }
  std::ostringstream json;
  json << "{\"advanced_boxes\": " << boxes << ", \"tables\": [";
  // The visible tables and their labels, for the picture.
  std::vector<std::pair<QWidget*, QLabel*>> rows;
  const char* separator = "";
  for (const std::string& name : wanted)
  {
    pqPropertyWidget* found = nullptr;
    for (QWidget* widget : QApplication::allWidgets())
    {
      auto* candidate = qobject_cast<pqPropertyWidget*>(widget);
      if (candidate && candidate->property() && candidate->proxy() &&
        name == candidate->property()->GetXMLName() &&
        std::string(proxyXmlName ? proxyXmlName : "") == candidate->proxy()->GetXMLName() &&
        (!found || candidate->isVisible()))
      {
        found = candidate;
      }
    }
    json << separator << "{\"property\": " << Quote(QString::fromStdString(name));
    separator = ", ";
    if (!found)
    {
      json << ", \"found\": false}";
      continue;
    }
    const char* xmlLabel = found->property()->GetXMLLabel();
    QLabel* label = LabelOf(found, QString(xmlLabel ? xmlLabel : ""));
    // The first hidden widget on the way up, if any (what keeps it from view).
    std::string hiddenBy = "null";
    for (QWidget* up = found; up; up = up->parentWidget())
    {
      if (up->isHidden())
      {
        hiddenBy = Quote(QString(up->metaObject()->className()) + " " + up->objectName());
        break;
      }
    }
    json << ", \"found\": true, \"visible\": " << (found->isVisible() ? "true" : "false")
         << ", \"hidden_by\": " << hiddenBy
         << ", \"label\": " << (label ? Quote(PlainText(label->text())) : std::string("null"));
    QTableView* table = found->findChild<QTableView*>();
    json << ", \"header_visible\": "
         << (table && table->horizontalHeader() && !table->horizontalHeader()->isHidden()
                ? "true"
                : "false")
         << ", \"headers\": [";
    if (table && table->model())
    {
      for (int c = 0; c < table->model()->columnCount(); ++c)
      {
        json << (c ? ", " : "")
             << Quote(table->model()->headerData(c, Qt::Horizontal, Qt::DisplayRole).toString());
      }
    }
    json << "]}";
    if (found->isVisible())
    {
      rows.emplace_back(found, label);
    }
  }
  json << "], \"picture\": ";
  bool saved = false;
  if (!rows.empty() && pngPath && *pngPath)
  {
    // Each table with its label, rendered by the widgets themselves
    // (QWidget::grab: independent of the panel's size and scroll position)
    // and stacked as the panel lays them out: labels left, tables right.
    int labelWidth = 0, tableWidth = 0, height = 0;
    for (const auto& row : rows)
    {
      labelWidth = std::max(labelWidth, row.second ? row.second->width() : 0);
      tableWidth = std::max(tableWidth, row.first->width());
      height += std::max(row.first->height(), row.second ? row.second->height() : 0) + 6;
    }
    QPixmap picture(labelWidth + 6 + tableWidth, height);
    picture.fill(rows.front().first->palette().color(QPalette::Window));
    QPainter painter(&picture);
    int y = 0;
    for (const auto& row : rows)
    {
      const int rowHeight = std::max(row.first->height(), row.second ? row.second->height() : 0);
      if (row.second)
      {
        painter.drawPixmap(0, y + (rowHeight - row.second->height()) / 2, row.second->grab());
      }
      painter.drawPixmap(labelWidth + 6, y, row.first->grab());
      y += rowHeight + 6;
    }
    painter.end();
    saved = picture.save(QString::fromUtf8(pngPath), "PNG");
  }
  json << (saved ? Quote(QString::fromUtf8(pngPath)) : std::string("null")) << "}";
  result = json.str();
  return result.c_str();
}
