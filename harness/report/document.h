#pragma once
// A report as a list of sections of paragraphs, tables and figures, rendered twice from the same content:
// as one HTML page (inline CSS, images referenced by relative path) and as its Markdown twin. Keeping one
// model means the two never disagree on a number.

#include <string>
#include <vector>

namespace twinray::report {

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<bool> numeric;  // per column: right-aligned (default: every column but the first)
};

struct Figure {
  std::string path;     // relative to the report folder
  std::string caption;
  bool wide = true;     // full width (plots) or a thumbnail in a row of images
};

struct Block {
  enum class Kind { Paragraph, Bullets, Table, Figures, Code } kind = Kind::Paragraph;
  std::string text;                 // Paragraph, Code
  std::vector<std::string> items;   // Bullets
  Table table;
  std::vector<Figure> figures;      // shown side by side when not wide
};

struct Section {
  std::string title;
  std::vector<Block> blocks;

  void paragraph(std::string text) { blocks.push_back({Block::Kind::Paragraph, std::move(text), {}, {}, {}}); }
  void bullets(std::vector<std::string> items) { blocks.push_back({Block::Kind::Bullets, {}, std::move(items), {}, {}}); }
  void table(Table t) { blocks.push_back({Block::Kind::Table, {}, {}, std::move(t), {}}); }
  void figures(std::vector<Figure> f) { blocks.push_back({Block::Kind::Figures, {}, {}, {}, std::move(f)}); }
  void code(std::string text) { blocks.push_back({Block::Kind::Code, std::move(text), {}, {}, {}}); }
};

struct Document {
  std::string title;
  std::string subtitle;
  std::vector<Section> sections;
};

std::string to_html(const Document& doc);
std::string to_markdown(const Document& doc);

// Every image path the document references (for checks).
std::vector<std::string> referenced_images(const Document& doc);

}  // namespace twinray::report
