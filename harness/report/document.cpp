#include "harness/report/document.h"

#include <fmt/core.h>

namespace twinray::report {

namespace {

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Markdown table cells: a literal '|' would end the cell.
std::string md_cell(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else if (c == '\n') out += ' ';
    else out += c;
  }
  return out;
}

std::string anchor(const std::string& title) {
  std::string a;
  for (char c : title) {
    if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9')) a += c;
    else if (c >= 'A' && c <= 'Z') a += static_cast<char>(c - 'A' + 'a');
    else if (c == ' ' || c == '-') a += '-';
  }
  return a;
}

bool is_numeric(const Table& t, std::size_t col) {
  return col < t.numeric.size() ? t.numeric[col] : col > 0;
}

constexpr const char* kCss = R"(body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
h1{margin-bottom:.2em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
.subtitle{color:#666;margin-top:0}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.25em .6em}th{background:#f3f3f3}td.num{text-align:right;font-variant-numeric:tabular-nums}
tr:nth-child(even) td{background:#fafafa}
figure{margin:1em 0}figure.wide img{max-width:100%;height:auto;border:1px solid #eee}
.row{display:flex;flex-wrap:wrap;gap:1em}.row figure{flex:0 0 auto;margin:0}.row img{width:256px;height:auto;image-rendering:pixelated;border:1px solid #ddd}
figcaption{font-size:.85em;color:#555;max-width:600px}
pre{background:#f6f6f6;padding:.8em;overflow-x:auto;font-size:.85em}
nav ul{columns:2}
)";

}  // namespace

std::string to_html(const Document& doc) {
  std::string h = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  h += fmt::format("<title>{}</title>\n<style>\n{}</style>\n</head>\n<body>\n", html_escape(doc.title), kCss);
  h += fmt::format("<h1>{}</h1>\n", html_escape(doc.title));
  if (!doc.subtitle.empty()) h += fmt::format("<p class=\"subtitle\">{}</p>\n", html_escape(doc.subtitle));
  h += "<nav><ul>\n";
  for (const Section& s : doc.sections)
    h += fmt::format("<li><a href=\"#{}\">{}</a></li>\n", anchor(s.title), html_escape(s.title));
  h += "</ul></nav>\n";
  for (const Section& s : doc.sections) {
    h += fmt::format("<h2 id=\"{}\">{}</h2>\n", anchor(s.title), html_escape(s.title));
    for (const Block& b : s.blocks) {
      switch (b.kind) {
        case Block::Kind::Paragraph: h += fmt::format("<p>{}</p>\n", html_escape(b.text)); break;
        case Block::Kind::Code: h += fmt::format("<pre>{}</pre>\n", html_escape(b.text)); break;
        case Block::Kind::Bullets:
          h += "<ul>\n";
          for (const std::string& item : b.items) h += fmt::format("<li>{}</li>\n", html_escape(item));
          h += "</ul>\n";
          break;
        case Block::Kind::Table: {
          h += "<table>\n<tr>";
          for (const std::string& c : b.table.header) h += fmt::format("<th>{}</th>", html_escape(c));
          h += "</tr>\n";
          for (const auto& row : b.table.rows) {
            h += "<tr>";
            for (std::size_t i = 0; i < row.size(); ++i)
              h += fmt::format("<td{}>{}</td>", is_numeric(b.table, i) ? " class=\"num\"" : "", html_escape(row[i]));
            h += "</tr>\n";
          }
          h += "</table>\n";
          break;
        }
        case Block::Kind::Figures: {
          const bool wide = !b.figures.empty() && b.figures.front().wide;
          if (!wide) h += "<div class=\"row\">\n";
          for (const Figure& f : b.figures)
            h += fmt::format("<figure class=\"{}\"><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                             wide ? "wide" : "thumb", html_escape(f.path), html_escape(f.caption), html_escape(f.caption));
          if (!wide) h += "</div>\n";
          break;
        }
      }
    }
  }
  h += "</body>\n</html>\n";
  return h;
}

std::string to_markdown(const Document& doc) {
  std::string m = fmt::format("# {}\n\n", doc.title);
  if (!doc.subtitle.empty()) m += fmt::format("_{}_\n\n", doc.subtitle);
  for (const Section& s : doc.sections) {
    m += fmt::format("## {}\n\n", s.title);
    for (const Block& b : s.blocks) {
      switch (b.kind) {
        case Block::Kind::Paragraph: m += b.text + "\n\n"; break;
        case Block::Kind::Code: m += "```\n" + b.text + "\n```\n\n"; break;
        case Block::Kind::Bullets:
          for (const std::string& item : b.items) m += "- " + item + "\n";
          m += "\n";
          break;
        case Block::Kind::Table: {
          m += "|";
          // Appended piece by piece: GCC 12 warns (-Wstringop-overflow, a false positive) on the temporary that
          // " " + cell + " |" builds, and appending avoids the temporary anyway.
          for (const std::string& c : b.table.header) m.append(" ").append(md_cell(c)).append(" |");
          m += "\n|";
          for (std::size_t i = 0; i < b.table.header.size(); ++i) m += is_numeric(b.table, i) ? "---:|" : "---|";
          m += "\n";
          for (const auto& row : b.table.rows) {
            m += "|";
            for (const std::string& c : row) m.append(" ").append(md_cell(c)).append(" |");
            m += "\n";
          }
          m += "\n";
          break;
        }
        case Block::Kind::Figures:
          // Wide figures (plots) each get their caption below; thumbnails sit in one paragraph, side by side.
          for (const Figure& f : b.figures)
            m += f.wide ? fmt::format("![{}]({})\n\n_{}_\n\n", md_cell(f.caption), f.path, f.caption)
                        : fmt::format("![{}]({}) ", md_cell(f.caption), f.path);
          if (!b.figures.empty() && !b.figures.front().wide) m += "\n\n";
          break;
      }
    }
  }
  return m;
}

std::vector<std::string> referenced_images(const Document& doc) {
  std::vector<std::string> paths;
  for (const Section& s : doc.sections)
    for (const Block& b : s.blocks)
      for (const Figure& f : b.figures) paths.push_back(f.path);
  return paths;
}

}  // namespace twinray::report
